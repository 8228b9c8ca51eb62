#include "synth.h"
#include "test_support.h"

#include <math.h>

#include "rsm/status.h"

/* ---- random numbers ------------------------------------------------------ */

void rsm_synth_rng_seed(rsm_synth_rng_t *rng, uint32_t seed)
{
    rng->s = seed != 0u ? seed : 0x9E3779B9u;
}

uint32_t rsm_synth_rng_next(rsm_synth_rng_t *rng)
{
    return rsm_test_rng_next(&rng->s);
}

float rsm_synth_rng_uniform(rsm_synth_rng_t *rng)
{
    return (float)(rsm_synth_rng_next(rng) >> 8) * (1.0f / 16777216.0f);
}

float rsm_synth_rng_gauss(rsm_synth_rng_t *rng)
{
    float sum = 0.0f;
    int k;
    for (k = 0; k < 12; ++k) {
        sum += rsm_synth_rng_uniform(rng);
    }
    return sum - 6.0f;
}

/* ---- worlds ---------------------------------------------------------------- */

/* The L-corridor with its niches; shared by both worlds. The first entry
 * closes the corridor's west end and is used only by the corridor world. */
#define RSM_SYNTH_CORRIDOR                                                                                    \
    {4.8f, -0.4f, 4.8f, 1.4f}, /* east wall, south part */                                                \
        {4.8f, 1.4f, 5.0f, 1.4f}, {5.0f, 1.4f, 5.0f, 1.7f}, {5.0f, 1.7f, 4.8f, 1.7f}, /* east niche */     \
        {4.8f, 1.7f, 4.8f, 3.2f},                                                     /* east wall, north */ \
        {4.8f, 3.2f, 4.0f, 3.2f},                                                     /* far end */          \
        {4.0f, 3.2f, 4.0f, 0.4f},                                                     /* inner wall */       \
        {4.0f, 0.4f, 2.0f, 0.4f},                                                     /* north wall */       \
        {2.0f, -0.4f, 3.0f, -0.4f},                                                   /* south wall, west */ \
        {3.0f, -0.4f, 3.0f, -0.6f}, {3.0f, -0.6f, 3.3f, -0.6f}, {3.3f, -0.6f, 3.3f, -0.4f}, /* niche */     \
        {3.3f, -0.4f, 4.8f, -0.4f} /* south wall, east */

static const rsm_synth_segment_t room_segments[] = {
    /* south wall with its alcove */
    {-2.0f, -1.5f, -0.3f, -1.5f},
    {-0.3f, -1.5f, -0.3f, -1.8f},
    {-0.3f, -1.8f, 0.3f, -1.8f},
    {0.3f, -1.8f, 0.3f, -1.5f},
    {0.3f, -1.5f, 2.0f, -1.5f},
    /* east wall with the doorway */
    {2.0f, -1.5f, 2.0f, -0.4f},
    {2.0f, 0.4f, 2.0f, 1.5f},
    /* north and west walls */
    {2.0f, 1.5f, -2.0f, 1.5f},
    {-2.0f, 1.5f, -2.0f, -1.5f},
    /* inner box */
    {0.5f, 0.2f, 1.1f, 0.2f},
    {1.1f, 0.2f, 1.1f, 0.6f},
    {1.1f, 0.6f, 0.5f, 0.6f},
    {0.5f, 0.6f, 0.5f, 0.2f},
    /* pillar */
    {-1.0f, -0.6f, -0.8f, -0.6f},
    {-0.8f, -0.6f, -0.8f, -0.4f},
    {-0.8f, -0.4f, -1.0f, -0.4f},
    {-1.0f, -0.4f, -1.0f, -0.6f},
    /* the L-corridor beyond the doorway */
    RSM_SYNTH_CORRIDOR,
};

static const rsm_synth_segment_t corridor_segments[] = {
    {2.0f, -0.4f, 2.0f, 0.4f}, /* closed west end */
    RSM_SYNTH_CORRIDOR,
};

rsm_synth_world_t rsm_synth_world_room(void)
{
    rsm_synth_world_t w;
    w.seg = room_segments;
    w.count = sizeof room_segments / sizeof room_segments[0];
    return w;
}

rsm_synth_world_t rsm_synth_world_corridor(void)
{
    rsm_synth_world_t w;
    w.seg = corridor_segments;
    w.count = sizeof corridor_segments / sizeof corridor_segments[0];
    return w;
}

float rsm_synth_cast(const rsm_synth_world_t *world, float ox, float oy, float angle_rad, float max_range_m)
{
    /* Double precision inside: the caster is the ground truth, so its own
     * rounding should stay far below anything the tests measure. */
    const double dx = cos((double)angle_rad);
    const double dy = sin((double)angle_rad);
    double best = (double)max_range_m;
    size_t k;
    for (k = 0; k < world->count; ++k) {
        const rsm_synth_segment_t *s = &world->seg[k];
        const double ex = (double)s->x1 - (double)s->x0;
        const double ey = (double)s->y1 - (double)s->y0;
        const double wx = (double)s->x0 - (double)ox;
        const double wy = (double)s->y0 - (double)oy;
        const double den = dx * ey - dy * ex; /* cross(d, e) */
        double t;
        double u;
        if (fabs(den) < 1.0e-12) {
            continue; /* parallel: a grazing ray sees nothing */
        }
        t = (wx * ey - wy * ex) / den; /* cross(w, e) / cross(d, e) */
        u = (wx * dy - wy * dx) / den; /* cross(w, d) / cross(d, e) */
        if (t > 0.0 && t < best && u >= 0.0 && u <= 1.0) {
            best = t;
        }
    }
    return (float)best;
}

/* ---- scans ------------------------------------------------------------------ */

rsm_synth_scan_config_t rsm_synth_scan_config_default(void)
{
    rsm_synth_scan_config_t c;
    c.beams = 181u;
    c.start_rad = -0.5f * RSM_PI;
    c.end_rad = 0.5f * RSM_PI;
    c.max_range_m = 20.0f;
    c.sigma_m = 0.0f;
    c.outlier_fraction = 0.0f;
    c.outlier_min_m = 0.1f;
    c.outlier_max_m = 4.0f;
    return c;
}

int rsm_synth_ranges(const rsm_synth_world_t *world, const rsm_pose_t *pose, const rsm_synth_scan_config_t *cfg,
                     rsm_synth_rng_t *rng, float *range_m, float *angle_rad, size_t cap)
{
    size_t n;
    size_t need;
    size_t i;
    float step;
    if (world == NULL || pose == NULL || cfg == NULL || range_m == NULL || angle_rad == NULL || cfg->beams < 2u ||
        cfg->beams > cap || !(cfg->outlier_fraction >= 0.0f && cfg->outlier_fraction <= 1.0f) ||
        !(cfg->max_range_m > 0.0f) || !(cfg->sigma_m >= 0.0f) ||
        (rng == NULL && (cfg->sigma_m > 0.0f || cfg->outlier_fraction > 0.0f))) {
        return RSM_ERR_INVAL;
    }
    n = cfg->beams;
    step = (cfg->end_rad - cfg->start_rad) / (float)(n - 1u);
    for (i = 0; i < n; ++i) {
        const float a = cfg->start_rad + step * (float)i;
        float r = rsm_synth_cast(world, pose->x, pose->y, pose->theta + a, cfg->max_range_m);
        if (r < cfg->max_range_m && cfg->sigma_m > 0.0f) {
            r += cfg->sigma_m * rsm_synth_rng_gauss(rng);
            if (r < 0.01f) {
                r = 0.01f;
            }
            if (r >= cfg->max_range_m) {
                r = 0.999f * cfg->max_range_m;
            }
        }
        angle_rad[i] = a;
        range_m[i] = r;
    }
    /* Exactly round(fraction * n) distinct readings become outliers, chosen
     * by selection sampling (Knuth's algorithm S): no scratch memory. */
    need = (size_t)(cfg->outlier_fraction * (float)n + 0.5f);
    if (need > n) {
        need = n;
    }
    for (i = 0; i < n && need > 0u; ++i) {
        if ((size_t)(rsm_synth_rng_next(rng) % (uint32_t)(n - i)) < need) {
            range_m[i] = cfg->outlier_min_m + (cfg->outlier_max_m - cfg->outlier_min_m) * rsm_synth_rng_uniform(rng);
            --need;
        }
    }
    return RSM_OK;
}

/* ---- paths and odometry -------------------------------------------------------- */

/* Local pose algebra in double precision (this file calls nothing in rsm). */
static double wrap_d(double a)
{
    const double two_pi = 6.283185307179586476925;
    const double pi = 3.141592653589793238463;
    a = fmod(a, two_pi);
    if (a > pi) {
        a -= two_pi;
    }
    if (a <= -pi) {
        a += two_pi;
    }
    return a;
}

static rsm_pose_t compose(const rsm_pose_t *a, double bx, double by, double bt)
{
    const double c = cos((double)a->theta);
    const double s = sin((double)a->theta);
    rsm_pose_t r;
    r.x = (float)((double)a->x + c * bx - s * by);
    r.y = (float)((double)a->y + s * bx + c * by);
    r.theta = (float)wrap_d((double)a->theta + bt);
    return r;
}

static size_t steps_for(float v, float step)
{
    const float q = fabsf(v) / step;
    size_t n = (size_t)q;
    if ((float)n < q) {
        ++n;
    }
    return n;
}

size_t rsm_synth_path(const rsm_pose_t *start, const rsm_synth_leg_t *legs, size_t nlegs, float step_m,
                      float step_rad, rsm_pose_t *out, size_t cap)
{
    size_t count = 0;
    size_t l;
    if (start == NULL || (nlegs > 0u && legs == NULL) || out == NULL || cap == 0u || !(step_m > 0.0f) ||
        !(step_rad > 0.0f)) {
        return 0u;
    }
    out[count++] = *start;
    for (l = 0; l < nlegs; ++l) {
        size_t n = steps_for(legs[l].forward_m, step_m);
        const size_t nt = steps_for(legs[l].turn_rad, step_rad);
        size_t k;
        double d;
        double phi;
        if (nt > n) {
            n = nt;
        }
        if (n == 0u) {
            n = 1u;
        }
        d = (double)legs[l].forward_m / (double)n;
        phi = (double)legs[l].turn_rad / (double)n;
        for (k = 0; k < n; ++k) {
            if (count >= cap) {
                return count;
            }
            out[count] = compose(&out[count - 1u], d * cos(0.5 * phi), d * sin(0.5 * phi), phi);
            ++count;
        }
    }
    return count;
}

rsm_motion_t rsm_synth_motion(const rsm_pose_t *from, const rsm_pose_t *to, const rsm_synth_odo_error_t *err)
{
    /* between(from, to) = inverse(from) (+) to */
    const double c = cos((double)from->theta);
    const double s = sin((double)from->theta);
    const double wx = (double)to->x - (double)from->x;
    const double wy = (double)to->y - (double)from->y;
    double dx = c * wx + s * wy;
    double dy = -s * wx + c * wy;
    double dt = wrap_d((double)to->theta - (double)from->theta);
    rsm_motion_t u;
    if (err != NULL) {
        const double dist = sqrt(dx * dx + dy * dy);
        dx *= 1.0 + (double)err->scale;
        dy *= 1.0 + (double)err->scale;
        dt = wrap_d(dt + (double)err->drift_rad_per_m * dist);
    }
    u.dx = (float)dx;
    u.dy = (float)dy;
    u.dtheta = (float)dt;
    return u;
}

/* ---- error measures -------------------------------------------------------------- */

float rsm_synth_pos_error(const rsm_pose_t *a, const rsm_pose_t *b)
{
    const float dx = a->x - b->x;
    const float dy = a->y - b->y;
    return sqrtf(dx * dx + dy * dy);
}

float rsm_synth_angle_error(const rsm_pose_t *a, const rsm_pose_t *b)
{
    return (float)fabs(wrap_d((double)a->theta - (double)b->theta));
}

int rsm_synth_pose_finite(const rsm_pose_t *p)
{
    return isfinite(p->x) && isfinite(p->y) && isfinite(p->theta);
}
