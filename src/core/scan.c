#include "core/hot.h" /* first: speed over size */
#include "rsm/scan.h"

#include <math.h>
#include <string.h>

#include "rsm/status.h"
#include "core/bits.h"
#include "core/check.h"
#include "core/fmath.h"

rsm_scan_limits_t rsm_scan_limits_default(void)
{
    rsm_scan_limits_t l;
    l.min_range_m = 0.05f;
    l.max_range_m = 20.0f;
    return l;
}

int rsm_scan_set_uniform_checked(rsm_scan_t *scan, size_t scan_size, unsigned long fingerprint, size_t count,
                                 float start_rad, float step_rad)
{
    size_t i;
    if (!RSM_SAME_BUILD(rsm_scan_t, scan_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (scan == NULL) {
        return RSM_ERR_INVAL;
    }
    if (count > RSM_MAX_BEAMS) {
        return RSM_ERR_NOMEM;
    }
    for (i = 0; i < count; ++i) {
        scan->angle_rad[i] = start_rad + step_rad * (float)i;
    }
    scan->count = count;
    return RSM_OK;
}

/* rsm_scan_reading_ok for the library's own scans. */
static int reading_ok(const rsm_scan_t *scan, size_t i, const rsm_scan_limits_t *lim, rsm_scan_drops_t *drops)
{
    float r;
    /* Out-of-range indices and missing arguments are not readings: refused,
     * and not counted as drops. */
    if (scan == NULL || lim == NULL || i >= scan->count || i >= RSM_MAX_BEAMS) {
        return 0;
    }
    r = scan->range_m[i];
    if (!isfinite(r) || !isfinite(scan->angle_rad[i])) {
        if (drops != NULL) {
            drops->nan++;
        }
        return 0;
    }
    if (r <= lim->min_range_m) {
        if (drops != NULL) {
            drops->too_short++;
        }
        return 0;
    }
    if (r >= lim->max_range_m) {
        if (drops != NULL) {
            drops->too_long++;
        }
        return 0;
    }
    return 1;
}

int rsm_scan_reading_ok_checked(const rsm_scan_t *scan, size_t scan_size, unsigned long fingerprint, size_t i,
                                const rsm_scan_limits_t *lim, rsm_scan_drops_t *drops)
{
    return RSM_SAME_BUILD(rsm_scan_t, scan_size, fingerprint) ? reading_ok(scan, i, lim, drops) : 0;
}

static int to_points(const rsm_scan_t *scan, const rsm_scan_limits_t *lim, rsm_scan_trig_t *trig, rsm_point_t *out,
                     size_t cap, rsm_scan_drops_t *drops)
{
    size_t i;
    size_t n = 0;
    if (scan == NULL || lim == NULL || out == NULL || scan->count > RSM_MAX_BEAMS) {
        return RSM_ERR_INVAL;
    }
    for (i = 0; i < scan->count && n < cap; ++i) {
        if (reading_ok(scan, i, lim, drops)) {
            const float a = scan->angle_rad[i];
            float c;
            float s;
            if (trig == NULL) {
                rsm_sincosf(a, &s, &c);
            } else {
                /* Compared as bits: -0 and 0 have sines of opposite sign
                 * (copies, not memcmp, which is a call per beam on the M4). */
                uint32_t now;
                uint32_t was;
                memcpy(&now, &a, sizeof now);
                memcpy(&was, &trig->angle[i], sizeof was);
                if (now != was) {
                    trig->angle[i] = a;
                    rsm_sincosf(a, &trig->sin[i], &trig->cos[i]);
                }
                c = trig->cos[i];
                s = trig->sin[i];
            }
            out[n].x = scan->range_m[i] * c;
            out[n].y = scan->range_m[i] * s;
            ++n;
        }
    }
    return (int)n;
}

int rsm_scan_to_points_checked(const rsm_scan_t *scan, size_t scan_size, unsigned long fingerprint,
                               const rsm_scan_limits_t *lim, rsm_point_t *out, size_t cap, rsm_scan_drops_t *drops)
{
    if (!RSM_SAME_BUILD(rsm_scan_t, scan_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    return to_points(scan, lim, NULL, out, cap, drops);
}

int rsm_scan_trig_init_checked(rsm_scan_trig_t *trig, size_t trig_size, unsigned long fingerprint)
{
    size_t i;
    if (!RSM_SAME_BUILD(rsm_scan_trig_t, trig_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (trig == NULL) {
        return RSM_ERR_INVAL;
    }
    for (i = 0; i < (size_t)RSM_MAX_BEAMS; ++i) {
        trig->angle[i] = NAN; /* no finite angle has its bits */
    }
    return RSM_OK;
}

int rsm_scan_to_points_cached_checked(const rsm_scan_t *scan, size_t scan_size, unsigned long fingerprint,
                                      const rsm_scan_limits_t *lim, rsm_scan_trig_t *trig, rsm_point_t *out,
                                      size_t cap, rsm_scan_drops_t *drops)
{
    if (!RSM_SAME_BUILD(rsm_scan_t, scan_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (trig == NULL) {
        return RSM_ERR_INVAL;
    }
    return to_points(scan, lim, trig, out, cap, drops);
}

/* Whether q continues p's surface (see rsm_points_isolated). */
static int same_surface(const rsm_point_t *o, const rsm_point_t *p, const rsm_point_t *q, float rp,
                        const rsm_isolation_t *iso)
{
    const float dx = q->x - p->x;
    const float dy = q->y - p->y;
    const float gap = fabsf((p->x - o->x) * (q->y - o->y) - (p->y - o->y) * (q->x - o->x)) / rp;
    const float lim = iso->tol_m + iso->slope * gap;
    return dx * dx + dy * dy <= lim * lim;
}

size_t rsm_points_isolated(const rsm_point_t *pts, size_t n, const rsm_point_t *origin, const rsm_isolation_t *iso,
                           uint8_t *mask)
{
    static const rsm_point_t zero = {0.0f, 0.0f};
    const rsm_point_t *o = origin != NULL ? origin : &zero;
    size_t marked = 0;
    size_t i;
    size_t w;
    if (pts == NULL || iso == NULL || mask == NULL) {
        return 0u;
    }
    memset(mask, 0, (n + 7u) / 8u);
    if (!(iso->tol_m > 0.0f) || iso->window == 0u) {
        return 0u;
    }
    w = iso->window < RSM_ISOLATION_MAX_WINDOW ? iso->window : RSM_ISOLATION_MAX_WINDOW;
    for (i = 0; i < n; ++i) {
        const rsm_point_t *p = &pts[i];
        const float rp = sqrtf((p->x - o->x) * (p->x - o->x) + (p->y - o->y) * (p->y - o->y));
        uint32_t agree = 0;
        size_t k;
        for (k = 1; k <= w && agree < iso->agree && rp > 0.0f; ++k) {
            agree += (k <= i && same_surface(o, p, &pts[i - k], rp, iso)) ? 1u : 0u;
            agree += (i + k < n && same_surface(o, p, &pts[i + k], rp, iso)) ? 1u : 0u;
        }
        if (agree < iso->agree) {
            rsm_bit_set(mask, i);
            ++marked;
        }
    }
    return marked;
}

/* Whether point i (range ri; need = ri less the margins) lies behind the
 * chord of p and q (ranges rp, rq, far the larger), all seen from (0, 0).
 * No divisions: each would cost more than the rest of the test on an M4. */
static int behind_chord(const rsm_point_t *p, const rsm_point_t *i, float ri, float need, const rsm_point_t *q,
                        float far, const rsm_occlusion_t *occ)
{
    const float dx = q->x - p->x;
    const float dy = q->y - p->y;
    const float d2 = dx * dx + dy * dy;
    const float cross_pq = p->x * q->y - p->y * q->x;
    /* One surface: |pq| <= tol_m + slope * |p x q| / far, times far. */
    const float lim = occ->tol_m * far + occ->slope * fabsf(cross_pq);
    float side_p;
    float side_q;
    float den;
    float num;
    if (d2 > occ->span_m * occ->span_m || d2 * far * far > lim * lim) {
        return 0;
    }
    /* i's beam must run between p's and q's (on the same side of each as
     * the other): a point beside both is not hidden by them. */
    side_p = p->x * i->y - p->y * i->x;
    side_q = i->x * q->y - i->y * q->x;
    if (!(side_p * cross_pq > 0.0f && side_q * cross_pq > 0.0f)) {
        return 0;
    }
    /* The beam meets the chord at range t = ri (p x d) / (i x d). */
    den = i->x * dy - i->y * dx;
    num = p->x * dy - p->y * dx;
    return den > 0.0f ? need * den > ri * num : (den < 0.0f && need * den < ri * num);
}

/* A pair of neighbours whose beams are farther apart than 10 degrees is
 * not taken as a surface across a beam between them. */
#define OCCLUSION_COS_MAX_ANGLE 0.9848f
/* The ring of ranges: a power of two above 2 * RSM_OCCLUSION_MAX_WINDOW. */
#define OCCLUSION_RING 16u
RSM_STATIC_ASSERT(occlusion_ring_holds_a_window, OCCLUSION_RING > 2u * RSM_OCCLUSION_MAX_WINDOW);
RSM_STATIC_ASSERT(occlusion_ring_is_a_power_of_two, (OCCLUSION_RING & (OCCLUSION_RING - 1u)) == 0u);

size_t rsm_points_occluded(const rsm_point_t *pts, size_t n, const rsm_occlusion_t *occ, uint8_t *mask)
{
    /* Ranges of the points i - w .. i + w, by index modulo the ring's size. */
    float ring[OCCLUSION_RING];
    const size_t last = OCCLUSION_RING - 1u;
    size_t marked = 0;
    size_t w;
    size_t i;
    size_t k;
    if (pts == NULL || occ == NULL || mask == NULL) {
        return 0u;
    }
    memset(mask, 0, (n + 7u) / 8u);
    if (occ->window == 0u || !(occ->span_m > 0.0f)) {
        return 0u;
    }
    w = occ->window < RSM_OCCLUSION_MAX_WINDOW ? occ->window : RSM_OCCLUSION_MAX_WINDOW;
    for (k = 0; k < w && k < n; ++k) {
        ring[k & last] = sqrtf(pts[k].x * pts[k].x + pts[k].y * pts[k].y);
    }
    for (i = 0; i < n; ++i) {
        const size_t lo = i < w ? 0u : i - w;
        const size_t hi = i + w < n ? i + w : n - 1u;
        float ri;
        float need;
        float nearest;
        size_t a;
        int hidden = 0;
        if (i + w < n) {
            ring[(i + w) & last] = sqrtf(pts[i + w].x * pts[i + w].x + pts[i + w].y * pts[i + w].y);
        }
        if (i == 0u || i + 1u >= n) {
            continue; /* no neighbour on one side */
        }
        ri = ring[i & last];
        need = ri - occ->margin_m - occ->margin_rel * ri;
        /* Along a beam between two neighbours' the chord lies at least
         * min(rp, rq) cos(angle p q) away: a point not that far behind the
         * nearest neighbour (most are not) is hidden by no pair. */
        nearest = ring[(i - 1u) & last];
        for (k = lo; k + 1u < i; ++k) {
            nearest = ring[k & last] < nearest ? ring[k & last] : nearest;
        }
        for (k = i + 1u; k <= hi; ++k) {
            nearest = ring[k & last] < nearest ? ring[k & last] : nearest;
        }
        if (!(need > OCCLUSION_COS_MAX_ANGLE * nearest)) {
            continue;
        }
        for (a = 1; a <= w && a <= i && !hidden; ++a) {
            const rsm_point_t *p = &pts[i - a];
            const float rp = ring[(i - a) & last];
            size_t b;
            for (b = 1; b <= w && i + b < n && !hidden; ++b) {
                const rsm_point_t *q = &pts[i + b];
                const float rq = ring[(i + b) & last];
                const float far = rp > rq ? rp : rq;
                float dot;
                /* Ranges further apart than span_m: not one surface (an
                 * edge, the commonest case here), known without p and q. */
                if (fabsf(rp - rq) > occ->span_m) {
                    continue;
                }
                dot = p->x * q->x + p->y * q->y;
                /* The same bound for this pair ((p . q) / far), and the
                 * pair's angle within the most allowed. */
                if (need * far > dot && dot >= OCCLUSION_COS_MAX_ANGLE * rp * rq) {
                    hidden = behind_chord(p, &pts[i], ri, need, q, far, occ);
                }
            }
        }
        if (hidden) {
            rsm_bit_set(mask, i);
            ++marked;
        }
    }
    return marked;
}
