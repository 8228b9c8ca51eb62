#include "paper/ransac.h"

#include <math.h>

#include "rsm/status.h"
#include "core/check.h"
#include "core/fmath.h"
#include "paper/rigid.h"

rsm_ransac_config_t rsm_ransac_config_default(void)
{
    rsm_ransac_config_t c;
    c.inlier_tol_m = 0.075f;
    c.length_tol_m = 0.1f;
    c.min_pair_sep_m = 0.2f;
    c.confidence = 0.99f;
    c.max_iterations = 300u;
    c.min_support = 5u;
    c.seed = 0x2545F491u;
    return c;
}

int rsm_ransac_config_check(const rsm_ransac_config_t *cfg, const char **field)
{
    RSM_CHECK_FIELD(cfg != NULL, "ransac");
    RSM_CHECK_FIELD(cfg->inlier_tol_m > 0.0f, "ransac.inlier_tol_m");
    RSM_CHECK_FIELD(cfg->length_tol_m > 0.0f, "ransac.length_tol_m");
    RSM_CHECK_FIELD(cfg->min_pair_sep_m >= 0.0f, "ransac.min_pair_sep_m");
    RSM_CHECK_FIELD(cfg->confidence > 0.0f && cfg->confidence < 1.0f, "ransac.confidence");
    RSM_CHECK_FIELD(cfg->max_iterations >= 1u, "ransac.max_iterations");
    RSM_CHECK_FIELD(cfg->min_support >= 2u, "ransac.min_support");
    return RSM_OK;
}

int rsm_ransac_init(rsm_ransac_t *rs, const rsm_ransac_config_t *cfg)
{
    if (rs == NULL || rsm_ransac_config_check(cfg, NULL) != RSM_OK) {
        return RSM_ERR_INVAL;
    }
    rs->cfg = cfg;
    rs->rng = cfg->seed != 0u ? cfg->seed : 0x2545F491u;
    return RSM_OK;
}

static uint32_t next_rand(rsm_ransac_t *rs)
{
    uint32_t x = rs->rng;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    rs->rng = x;
    return x;
}

/* Hypothesis from matches i and j; returns 0 if the sample is unusable. */
static int hypothesis(const rsm_ransac_config_t *cfg, const rsm_point_t *ref, const rsm_point_t *cur,
                      const rsm_match_t *mi, const rsm_match_t *mj, rsm_pose_t *t, uint32_t *length_rejects)
{
    const rsm_point_t *ci = &cur[mi->cur];
    const rsm_point_t *cj = &cur[mj->cur];
    const rsm_point_t *ri = &ref[mi->ref];
    const rsm_point_t *rj = &ref[mj->ref];
    const float a = ci->x - cj->x;
    const float b = ci->y - cj->y;
    const float c = ri->x - rj->x;
    const float d = ri->y - rj->y;
    const float lc = sqrtf(a * a + b * b);
    const float lr = sqrtf(c * c + d * d);
    float cs;
    float sn;
    if (mi->ref == mj->ref || mi->cur == mj->cur || lr < cfg->min_pair_sep_m) {
        return 0;
    }
    if (fabsf(lc - lr) > cfg->length_tol_m) {
        ++*length_rejects;
        return 0;
    }
    t->theta = rsm_atan2f(a * d - b * c, a * c + b * d);
    cs = rsm_cosf(t->theta);
    sn = rsm_sinf(t->theta);
    t->x = ri->x - (cs * ci->x - sn * ci->y);
    t->y = ri->y - (sn * ci->x + cs * ci->y);
    return 1;
}

/* Marks inliers of t (flags written when flags != NULL) and returns the
 * number of distinct reference points supported. Matches are grouped by
 * reference index, so a change of ref marks a new distinct point. */
static uint32_t support_of(const rsm_ransac_config_t *cfg, const rsm_point_t *ref, const rsm_point_t *cur,
                           const rsm_match_t *m, size_t nm, const rsm_pose_t *t, uint8_t *flags)
{
    const float cs = rsm_cosf(t->theta);
    const float sn = rsm_sinf(t->theta);
    const float tol2 = cfg->inlier_tol_m * cfg->inlier_tol_m;
    uint32_t count = 0;
    uint32_t last_ref = 0xFFFFFFFFu;
    size_t k;
    for (k = 0; k < nm; ++k) {
        const rsm_point_t *p = &cur[m[k].cur];
        const rsm_point_t *q = &ref[m[k].ref];
        const float ex = t->x + cs * p->x - sn * p->y - q->x;
        const float ey = t->y + sn * p->x + cs * p->y - q->y;
        const int in = ex * ex + ey * ey <= tol2;
        if (flags != NULL) {
            flags[k] = (uint8_t)in;
        }
        if (in && m[k].ref != last_ref) {
            ++count;
            last_ref = m[k].ref;
        }
    }
    return count;
}

/* Eq. 16 solved for n: iterations needed so that, with inlier ratio w, a
 * clean two-match sample is drawn with probability confidence. */
static uint32_t needed_iterations(float confidence, float w, uint32_t budget)
{
    const float p2 = w * w;
    float n;
    if (p2 >= 1.0f) {
        return 1u;
    }
    if (p2 <= 1.0e-6f) {
        return budget;
    }
    n = rsm_logf(1.0f - confidence) / rsm_logf(1.0f - p2);
    if (!(n < (float)budget)) {
        return budget;
    }
    return n < 1.0f ? 1u : (uint32_t)rsm_ceilf(n);
}

/* Least-squares refit over inliers, keeping the best match per reference. */
static int refine(rsm_ransac_t *rs, const rsm_point_t *ref, const rsm_point_t *cur, const rsm_match_t *m,
                  size_t nm, rsm_pose_t *t, float *rms)
{
    const float cs = rsm_cosf(t->theta);
    const float sn = rsm_sinf(t->theta);
    size_t k = 0;
    size_t n = 0;
    float sum = 0.0f;
    while (k < nm) {
        const uint16_t r = m[k].ref;
        size_t best = nm;
        float best_e = 0.0f;
        for (; k < nm && m[k].ref == r; ++k) {
            if (rs->inlier[k]) {
                const rsm_point_t *p = &cur[m[k].cur];
                const float ex = t->x + cs * p->x - sn * p->y - ref[r].x;
                const float ey = t->y + sn * p->x + cs * p->y - ref[r].y;
                const float e = ex * ex + ey * ey;
                if (best == nm || e < best_e) {
                    best = k;
                    best_e = e;
                }
            }
        }
        if (best != nm) {
            rs->src[n] = cur[m[best].cur];
            rs->dst[n] = ref[r];
            sum += best_e;
            ++n;
        }
    }
    if (n < 2) {
        return RSM_ERR_DEGENERATE;
    }
    *rms = sqrtf(sum / (float)n);
    return rsm_rigid_fit(rs->src, rs->dst, NULL, n, t);
}

int rsm_ransac_estimate(rsm_ransac_t *rs, const rsm_point_t *ref, const rsm_point_t *cur, const rsm_match_t *m,
                        size_t nm, rsm_ransac_result_t *res)
{
    const rsm_ransac_config_t *cfg;
    rsm_pose_t best_t = {0.0f, 0.0f, 0.0f};
    uint32_t best_support = 0;
    uint32_t needed;
    uint32_t it = 0;
    size_t pairs;
    int round;
    if (rs == NULL || rs->cfg == NULL || res == NULL || (nm > 0 && (ref == NULL || cur == NULL || m == NULL))) {
        return RSM_ERR_INVAL;
    }
    if (nm > RSM_MAX_MATCHES) {
        return RSM_ERR_NOMEM;
    }
    cfg = rs->cfg;
    res->t = best_t;
    res->support = 0;
    res->iterations = 0;
    res->length_rejects = 0;
    res->exhaustive = 0;
    res->rms_m = 0.0f;
    if (nm < 2) {
        return RSM_ERR_DEGENERATE;
    }
    pairs = nm * (nm - 1) / 2;
    needed = cfg->max_iterations;
    if (pairs <= (size_t)needed) {
        size_t i;
        size_t j;
        res->exhaustive = 1;
        for (i = 0; i < nm; ++i) {
            for (j = i + 1; j < nm; ++j) {
                rsm_pose_t t;
                ++it;
                if (hypothesis(cfg, ref, cur, &m[i], &m[j], &t, &res->length_rejects)) {
                    const uint32_t s = support_of(cfg, ref, cur, m, nm, &t, NULL);
                    if (s > best_support) {
                        best_support = s;
                        best_t = t;
                    }
                }
            }
        }
    } else {
        while (it < needed) {
            const size_t i = (size_t)(next_rand(rs) % (uint32_t)nm);
            const size_t j = (size_t)(next_rand(rs) % (uint32_t)nm);
            rsm_pose_t t;
            ++it;
            if (i != j && hypothesis(cfg, ref, cur, &m[i], &m[j], &t, &res->length_rejects)) {
                const uint32_t s = support_of(cfg, ref, cur, m, nm, &t, NULL);
                if (s > best_support) {
                    /* Distinct references bound the inlier ratio of eq. 16. */
                    const uint32_t nref = (uint32_t)m[nm - 1].ref + 1u;
                    best_support = s;
                    best_t = t;
                    needed = needed_iterations(cfg->confidence, (float)s / (float)(nref > s ? nref : s),
                                               cfg->max_iterations);
                }
            }
        }
    }
    res->iterations = it;
    res->support = best_support;
    if (best_support < cfg->min_support) {
        return RSM_ERR_DEGENERATE;
    }
    /* Two rounds of refit and re-selection settle the inlier set. */
    for (round = 0; round < 2; ++round) {
        rsm_pose_t t = best_t;
        float rms = 0.0f;
        (void)support_of(cfg, ref, cur, m, nm, &best_t, rs->inlier);
        if (refine(rs, ref, cur, m, nm, &t, &rms) != RSM_OK) {
            break;
        }
        if (support_of(cfg, ref, cur, m, nm, &t, NULL) < best_support) {
            break;
        }
        best_t = t;
        res->rms_m = rms;
    }
    res->support = support_of(cfg, ref, cur, m, nm, &best_t, rs->inlier);
    res->t = best_t;
    return RSM_OK;
}
