/* Differential-drive odometry: wheel ticks -> motion increment, plus the
 * motion model's Jacobians and process noise (see include/rsm/odometry.h). */
#include "rsm/odometry.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "rsm/status.h"
#include "core/check.h"
#include "core/fmath.h"

rsm_odometry_config_t rsm_odometry_config_default(void)
{
    rsm_odometry_config_t c;
    /* P3-DX: TicksMM = 128 in the ARIA robot parameter file, i.e. 128000
     * ticks per metre; calibrate per robot (tyre pressure moves it by %). */
    c.ticks_per_m_left = 128000.0f;
    c.ticks_per_m_right = 128000.0f;
    /* Effective track width of a P3-DX (DiffConvFactor-calibrated). */
    c.wheel_base_m = 0.357f;
    /* ARIA ENCODER packets carry full 32-bit counters. */
    c.counter_bits = 32u;
    /* 5 cm of translation error per metre driven. */
    c.sigma_trans_per_m = 0.05f;
    /* 0.05 rad of heading error per rad turned (about 3 deg per 60 deg). */
    c.sigma_rot_per_rad = 0.05f;
    /* 0.02 rad (about 1.1 deg) of heading drift per metre driven, from
     * unequal effective wheel radii. */
    c.sigma_rot_per_m = 0.02f;
    /* Floors so that a standing robot still has a positive-definite Q:
     * 2 mm and 2 mrad per step. */
    c.sigma_trans_min_m = 0.002f;
    c.sigma_rot_min_rad = 0.002f;
    /* Generous bounds: they only have to catch counts no robot produces. */
    c.max_wheel_speed_mps = 3.0f;
    c.max_turn_rate_rps = 4.0f * RSM_PI;
    c.slack_s = 1.0f;
    return c;
}

static int positive_finite(float v)
{
    return isfinite(v) && v > 0.0f;
}

static int non_negative_finite(float v)
{
    return isfinite(v) && v >= 0.0f;
}

int rsm_odometry_config_check(const rsm_odometry_config_t *cfg, const char **field)
{
    RSM_CHECK_FIELD(cfg != NULL, "odometry");
    RSM_CHECK_FIELD(positive_finite(cfg->ticks_per_m_left), "odometry.ticks_per_m_left");
    RSM_CHECK_FIELD(positive_finite(cfg->ticks_per_m_right), "odometry.ticks_per_m_right");
    RSM_CHECK_FIELD(positive_finite(cfg->wheel_base_m), "odometry.wheel_base_m");
    RSM_CHECK_FIELD(cfg->counter_bits >= 16u && cfg->counter_bits <= 32u, "odometry.counter_bits");
    RSM_CHECK_FIELD(non_negative_finite(cfg->sigma_trans_per_m), "odometry.sigma_trans_per_m");
    RSM_CHECK_FIELD(non_negative_finite(cfg->sigma_rot_per_rad), "odometry.sigma_rot_per_rad");
    RSM_CHECK_FIELD(non_negative_finite(cfg->sigma_rot_per_m), "odometry.sigma_rot_per_m");
    RSM_CHECK_FIELD(non_negative_finite(cfg->sigma_trans_min_m), "odometry.sigma_trans_min_m");
    RSM_CHECK_FIELD(non_negative_finite(cfg->sigma_rot_min_rad), "odometry.sigma_rot_min_rad");
    RSM_CHECK_FIELD(non_negative_finite(cfg->max_wheel_speed_mps), "odometry.max_wheel_speed_mps");
    RSM_CHECK_FIELD(non_negative_finite(cfg->max_turn_rate_rps), "odometry.max_turn_rate_rps");
    RSM_CHECK_FIELD(non_negative_finite(cfg->slack_s), "odometry.slack_s");
    return RSM_OK;
}

int rsm_odometry_init(rsm_odometry_t *odo, const rsm_odometry_config_t *cfg)
{
    if (odo == NULL || rsm_odometry_config_check(cfg, NULL) != RSM_OK) {
        return RSM_ERR_INVAL;
    }
    memset(odo, 0, sizeof *odo);
    odo->cfg = *cfg;
    return RSM_OK;
}

int rsm_odometry_set_config(rsm_odometry_t *odo, const rsm_odometry_config_t *cfg)
{
    if (odo == NULL || rsm_odometry_config_check(cfg, NULL) != RSM_OK) {
        return RSM_ERR_INVAL;
    }
    if (cfg->counter_bits != odo->cfg.counter_bits) {
        rsm_odometry_restart(odo); /* the latched counts were masked to the old width */
    }
    odo->cfg = *cfg;
    return RSM_OK;
}

void rsm_odometry_restart(rsm_odometry_t *odo)
{
    if (odo != NULL) {
        odo->have_last = 0u;
        odo->have_cand = 0u;
    }
}

static uint32_t counter_mask(uint8_t bits)
{
    /* A shift by 32 would be undefined. */
    return (bits >= 32u || bits == 0u) ? 0xFFFFFFFFu : ((1u << bits) - 1u);
}

int32_t rsm_odometry_count_delta(uint32_t to, uint32_t from, uint8_t bits)
{
    const uint32_t mask = counter_mask(bits);
    const uint32_t d = (to - from) & mask;
    uint32_t mag;
    if (d <= (mask >> 1)) {
        return (int32_t)d;
    }
    /* Negative: magnitude is 2^bits - d, in [1, 2^(bits-1)]. Built without
     * relying on implementation-defined unsigned-to-signed conversion. */
    mag = (mask - d) + 1u;
    if (mag > 0x7FFFFFFFu) {
        return INT32_MIN;
    }
    return -(int32_t)mag;
}

/* Seconds from an earlier stamp to a later one; 0 when either is unknown
 * or time went backwards. */
static float elapsed_s(uint8_t have_from, uint64_t from_us, uint64_t to_us)
{
    if (!have_from || to_us == RSM_ODOMETRY_NO_TIME || to_us < from_us) {
        return 0.0f;
    }
    {
        /* Whole seconds and microseconds apart: no double arithmetic, which
         * a Cortex-M4F does in software (and cross-check refuses). Beyond
         * 11 days the bounds catch nothing anyway. */
        const uint64_t d = to_us - from_us;
        const uint64_t whole = d / 1000000u;
        const float secs = whole > 1000000u ? 1.0e6f : (float)(uint32_t)whole;
        return secs + (float)(uint32_t)(d % 1000000u) * 1.0e-6f;
    }
}

/* Whether wheel steps of dl and dr ticks fit the configured rates over dt. */
static int plausible(const rsm_odometry_config_t *cfg, int32_t dl, int32_t dr, float dt)
{
    const float t = dt + cfg->slack_s;
    const float ml = (float)dl / cfg->ticks_per_m_left;
    const float mr = (float)dr / cfg->ticks_per_m_right;
    if (cfg->max_wheel_speed_mps > 0.0f &&
        (fabsf(ml) > cfg->max_wheel_speed_mps * t || fabsf(mr) > cfg->max_wheel_speed_mps * t)) {
        return 0;
    }
    /* The turn before wrapping: a step of several turns is not small. */
    if (cfg->max_turn_rate_rps > 0.0f && fabsf(mr - ml) / cfg->wheel_base_m > cfg->max_turn_rate_rps * t) {
        return 0;
    }
    return 1;
}

static void latch(rsm_odometry_t *odo, uint32_t left, uint32_t right, uint64_t stamp_us)
{
    odo->last_left = left;
    odo->last_right = right;
    odo->have_last = 1u;
    odo->have_time = stamp_us != RSM_ODOMETRY_NO_TIME;
    odo->last_us = stamp_us;
    odo->have_cand = 0u;
}

static void zero_motion(rsm_motion_t *out)
{
    out->dx = 0.0f;
    out->dy = 0.0f;
    out->dtheta = 0.0f;
}

int rsm_odometry_update_ticks_at(rsm_odometry_t *odo, uint32_t left, uint32_t right, uint64_t stamp_us,
                                 rsm_motion_t *out)
{
    const rsm_odometry_config_t *cfg;
    uint8_t bits;
    int32_t dl;
    int32_t dr;
    if (odo == NULL || out == NULL) {
        return RSM_ERR_INVAL;
    }
    cfg = &odo->cfg;
    bits = cfg->counter_bits;
    if (bits < 16u || bits > 32u) {
        return RSM_ERR_INVAL;
    }
    left &= counter_mask(bits);
    right &= counter_mask(bits);
    zero_motion(out);
    if (!odo->have_last) {
        latch(odo, left, right, stamp_us);
        return RSM_ERR_AGAIN;
    }
    dl = rsm_odometry_count_delta(left, odo->last_left, bits);
    dr = rsm_odometry_count_delta(right, odo->last_right, bits);
    if (!plausible(cfg, dl, dr, elapsed_s(odo->have_time, odo->last_us, stamp_us))) {
        if (odo->have_cand) {
            const int32_t cl = rsm_odometry_count_delta(left, odo->cand_left, bits);
            const int32_t cr = rsm_odometry_count_delta(right, odo->cand_right, bits);
            if (plausible(cfg, cl, cr, elapsed_s(odo->cand_has_time, odo->cand_us, stamp_us))) {
                /* The counters started over at the refused sample. */
                latch(odo, left, right, stamp_us);
                odo->relatched++;
                *out = rsm_odometry_from_ticks(cfg, cl, cr);
                odo->steps++;
                return RSM_OK;
            }
        }
        odo->implausible++;
        odo->have_cand = 1u;
        odo->cand_left = left;
        odo->cand_right = right;
        odo->cand_has_time = stamp_us != RSM_ODOMETRY_NO_TIME;
        odo->cand_us = stamp_us;
        return RSM_ERR_RANGE;
    }
    latch(odo, left, right, stamp_us);
    *out = rsm_odometry_from_ticks(cfg, dl, dr);
    odo->steps++;
    return RSM_OK;
}

int rsm_odometry_update_ticks(rsm_odometry_t *odo, uint32_t left, uint32_t right, rsm_motion_t *out)
{
    return rsm_odometry_update_ticks_at(odo, left, right, RSM_ODOMETRY_NO_TIME, out);
}

rsm_motion_t rsm_odometry_from_ticks(const rsm_odometry_config_t *cfg, int32_t d_left, int32_t d_right)
{
    rsm_motion_t u;
    float dl;
    float dr;
    float ds;
    float dth;
    u.dx = 0.0f;
    u.dy = 0.0f;
    u.dtheta = 0.0f;
    /* No status channel here: an unusable config gives the zero increment. */
    if (cfg == NULL || !positive_finite(cfg->ticks_per_m_left) || !positive_finite(cfg->ticks_per_m_right) ||
        !positive_finite(cfg->wheel_base_m)) {
        return u;
    }
    dl = (float)d_left / cfg->ticks_per_m_left;
    dr = (float)d_right / cfg->ticks_per_m_right;
    ds = 0.5f * (dl + dr);
    /* CCW positive: the right wheel running ahead turns the robot left. */
    dth = (dr - dl) / cfg->wheel_base_m;
    /* Chord at the mid heading: exact direction of the chord of a circular
     * arc, and a length error of only dS*dth^2/24. */
    rsm_sincosf(0.5f * dth, &u.dy, &u.dx);
    u.dx *= ds;
    u.dy *= ds;
    u.dtheta = rsm_wrap_angle(dth);
    return u;
}

rsm_motion_t rsm_odometry_from_poses(const rsm_pose_t *prev, const rsm_pose_t *cur)
{
    rsm_motion_t u;
    rsm_pose_t d;
    u.dx = 0.0f;
    u.dy = 0.0f;
    u.dtheta = 0.0f;
    if (prev == NULL || cur == NULL) {
        return u;
    }
    d = rsm_pose_between(prev, cur);
    u.dx = d.x;
    u.dy = d.y;
    u.dtheta = d.theta;
    return u;
}

rsm_pose_t rsm_odometry_apply(const rsm_pose_t *pose, const rsm_motion_t *u)
{
    rsm_pose_t b;
    if (pose == NULL) {
        b.x = 0.0f;
        b.y = 0.0f;
        b.theta = 0.0f;
        return b;
    }
    if (u == NULL) {
        return *pose;
    }
    b.x = u->dx;
    b.y = u->dy;
    b.theta = u->dtheta;
    return rsm_pose_compose(pose, &b);
}

void rsm_odometry_jacobians(const rsm_pose_t *pose, const rsm_motion_t *u, float jv[9], float ju[9])
{
    float c;
    float s;
    if (pose == NULL || u == NULL) {
        return;
    }
    rsm_sincosf(pose->theta, &s, &c);
    /* x' = x + c dx - s dy, y' = y + s dx + c dy, theta' = theta + dtheta. */
    if (jv != NULL) {
        jv[0] = 1.0f;
        jv[1] = 0.0f;
        jv[2] = -s * u->dx - c * u->dy;
        jv[3] = 0.0f;
        jv[4] = 1.0f;
        jv[5] = c * u->dx - s * u->dy;
        jv[6] = 0.0f;
        jv[7] = 0.0f;
        jv[8] = 1.0f;
    }
    if (ju != NULL) {
        ju[0] = c;
        ju[1] = -s;
        ju[2] = 0.0f;
        ju[3] = s;
        ju[4] = c;
        ju[5] = 0.0f;
        ju[6] = 0.0f;
        ju[7] = 0.0f;
        ju[8] = 1.0f;
    }
}

/* The noise of one step, with the distance terms' variance growing
 * linearly beyond a step of walk_m (0: never). */
static void step_noise(const rsm_odometry_config_t *cfg, const rsm_motion_t *u, float walk_m, float q[9])
{
    float ds;
    float dth;
    float st;
    float sr_turn;
    float sr_drift;
    float var_t;
    float var_r;
    float walked = 1.0f;
    int i;
    if (cfg == NULL || u == NULL || q == NULL) {
        return;
    }
    /* |dS| is the chord length; it differs from the arc length by a
     * negligible dS*dtheta^2/24 per step. */
    ds = sqrtf(u->dx * u->dx + u->dy * u->dy);
    dth = fabsf(u->dtheta);
    if (walk_m > 0.0f && ds > walk_m) {
        walked = walk_m / ds;
    }
    st = cfg->sigma_trans_per_m * ds;
    sr_turn = cfg->sigma_rot_per_rad * dth;
    sr_drift = cfg->sigma_rot_per_m * ds;
    var_t = st * st * walked + cfg->sigma_trans_min_m * cfg->sigma_trans_min_m;
    var_r = sr_turn * sr_turn + sr_drift * sr_drift * walked + cfg->sigma_rot_min_rad * cfg->sigma_rot_min_rad;
    for (i = 0; i < 9; ++i) {
        q[i] = 0.0f;
    }
    /* Isotropic translation noise (same variance along and across the
     * step), so Ju Q Ju^T does not depend on the heading. Across-track error
     * from a heading error within the step is only |dS|/2 times that error;
     * the heading variance carries it into x and y through Jv from the next
     * step on. A diagonal Q cannot hold the dy-dtheta correlation anyway. */
    q[0] = var_t;
    q[4] = var_t;
    q[8] = var_r;
    if (walked < 1.0f) {
        /* A walk of steps of walk_m: the heading's error grows along it
         * (variance sigma_rot_per_m^2 walk_m s after s metres), and the
         * position across the chord integrates it: variance
         * sigma_rot_per_m^2 walk_m dS^3 / 3, and dS^2 / 2 with the
         * heading's at the end (what the filter's Jacobians carry from
         * step to step when the same drive comes in ordinary steps). */
        const float k = cfg->sigma_rot_per_m * cfg->sigma_rot_per_m * walk_m;
        const float nx = -u->dy / ds;
        const float ny = u->dx / ds;
        const float across = k * ds * ds * ds / 3.0f;
        const float with_heading = k * ds * ds / 2.0f;
        q[0] += across * nx * nx;
        q[1] = across * nx * ny;
        q[3] = q[1];
        q[4] += across * ny * ny;
        q[2] = with_heading * nx;
        q[6] = q[2];
        q[5] = with_heading * ny;
        q[7] = q[5];
    }
}

void rsm_odometry_noise(const rsm_odometry_config_t *cfg, const rsm_motion_t *u, float q[9])
{
    step_noise(cfg, u, 0.0f, q);
}

void rsm_odometry_noise_walk(const rsm_odometry_config_t *cfg, const rsm_motion_t *u, float q[9])
{
    step_noise(cfg, u, RSM_ODOMETRY_WALK_STEP_M, q);
}

rsm_odometry_cal_config_t rsm_odometry_cal_config_default(void)
{
    rsm_odometry_cal_config_t c;
    c.memory = 1024.0f;
    c.prior = 0.01f;
    c.max_turn = 0.25f;
    c.max_drift = 0.1f;
    c.gate_rad = 0.1f;
    c.max_scale = 0.0f;
    c.gate_m = 0.05f;
    c.scale_prior_m = 1.0f;
    return c;
}

int rsm_odometry_cal_config_check(const rsm_odometry_cal_config_t *cfg, const char **field)
{
    RSM_CHECK_FIELD(cfg != NULL, "odometry_cal");
    RSM_CHECK_FIELD(cfg->memory == 0.0f || (cfg->memory >= 2.0f && cfg->memory <= 1e9f), "odometry_cal.memory");
    if (cfg->memory == 0.0f) {
        return RSM_OK; /* off: nothing else is read */
    }
    RSM_CHECK_FIELD(positive_finite(cfg->prior), "odometry_cal.prior");
    RSM_CHECK_FIELD(cfg->max_turn > 0.0f && cfg->max_turn < 1.0f, "odometry_cal.max_turn");
    RSM_CHECK_FIELD(positive_finite(cfg->max_drift), "odometry_cal.max_drift");
    RSM_CHECK_FIELD(positive_finite(cfg->gate_rad), "odometry_cal.gate_rad");
    RSM_CHECK_FIELD(cfg->max_scale >= 0.0f && cfg->max_scale < 1.0f, "odometry_cal.max_scale");
    RSM_CHECK_FIELD(positive_finite(cfg->gate_m), "odometry_cal.gate_m");
    RSM_CHECK_FIELD(positive_finite(cfg->scale_prior_m), "odometry_cal.scale_prior_m");
    return RSM_OK;
}

void rsm_odometry_cal_init(rsm_odometry_cal_t *cal)
{
    if (cal != NULL) {
        memset(cal, 0, sizeof *cal);
    }
}

/* Odometry's sums between two scans no robot makes: a turn over pi (the
 * heading change would wrap) or 10 m of travel. Within them (and the gate,
 * which a NaN fails) every sum stays finite and the system solvable. */
#define CAL_MAX_TRAVEL_M 10.0f

/* A step longer than the spans the correction is fitted on comes over a gap
 * in the scans: the correction needs the path (the turns summed, the metres
 * driven), and the step gives only its chord and its turn less whole turns
 * (on ACES a drift term of 0.022 rad/m times a 23 m chord turned a 120 s
 * step 30 degrees away; docs/faults.md). It is taken as reported. */
rsm_motion_t rsm_odometry_cal_apply(const rsm_odometry_cal_t *cal, const rsm_motion_t *u)
{
    rsm_motion_t v = *u;
    if (cal != NULL && u->dx * u->dx + u->dy * u->dy <= CAL_MAX_TRAVEL_M * CAL_MAX_TRAVEL_M) {
        v.dtheta = rsm_wrap_angle(u->dtheta * (1.0f + cal->k_turn) + cal->k_drift * u->dx);
        v.dx = u->dx * (1.0f + cal->k_scale);
        v.dy = u->dy * (1.0f + cal->k_scale);
    }
    return v;
}

/* Whether the distance is calibrated: else its bookkeeping is skipped. */
static int scaling(const rsm_odometry_cal_config_t *cfg)
{
    return cfg->max_scale > 0.0f;
}

void rsm_odometry_cal_count(rsm_odometry_cal_t *cal, const rsm_odometry_cal_config_t *cfg, const rsm_motion_t *u,
                            float var_t)
{
    if (cal == NULL || cfg == NULL || u == NULL) {
        return;
    }
    if (scaling(cfg)) {
        /* The step in the distance's reference frame, at odometry's
         * heading since then as corrected: over a corridor's span the raw
         * heading's drift would shorten the chord and turn it aside. */
        float c;
        float s;
        rsm_sincosf(cal->disp_turn, &s, &c);
        cal->disp[0] += c * u->dx - s * u->dy;
        cal->disp[1] += s * u->dx + c * u->dy;
        cal->disp_turn = rsm_wrap_angle(cal->disp_turn + u->dtheta * (1.0f + cal->k_turn) + cal->k_drift * u->dx);
        if (var_t > 0.0f) {
            cal->disp_var += var_t;
        }
    }
    cal->turn += u->dtheta;
    cal->travel += u->dx;
}

static void scale_reference(rsm_odometry_cal_t *cal, const rsm_pose_t *est, const float pos_cov[3])
{
    cal->sref = *est;
    cal->disp[0] = 0.0f;
    cal->disp[1] = 0.0f;
    cal->disp_turn = 0.0f;
    cal->disp_var = 0.0f;
    if (pos_cov != NULL) {
        memcpy(cal->sref_cov, pos_cov, sizeof cal->sref_cov);
    } else {
        memset(cal->sref_cov, 0, sizeof cal->sref_cov);
    }
}

static void heading_reference(rsm_odometry_cal_t *cal, const rsm_pose_t *est)
{
    cal->ref = *est;
    cal->have_ref = 1u;
    cal->turn = 0.0f;
    cal->travel = 0.0f;
}

void rsm_odometry_cal_reference(rsm_odometry_cal_t *cal, const rsm_pose_t *est)
{
    if (cal == NULL || est == NULL) {
        return;
    }
    heading_reference(cal, est);
    scale_reference(cal, est, NULL);
}

/* Below this odometry's displacement gives no direction to fit along. */
#define CAL_MIN_DISP_M 0.001f

/* The length of odometry's displacement since the distance's reference (NaN
 * or infinite if it is), and its unit direction in the world frame in dir
 * when that is finite and the length at least CAL_MIN_DISP_M (else dir[0]
 * is NaN). */
static float span(const rsm_odometry_cal_t *cal, float dir[2])
{
    const float s = sqrtf(cal->disp[0] * cal->disp[0] + cal->disp[1] * cal->disp[1]);
    dir[0] = NAN;
    if (s >= CAL_MIN_DISP_M) {
        float c;
        float sn;
        float x;
        float y;
        rsm_sincosf(cal->sref.theta, &sn, &c);
        x = (c * cal->disp[0] - sn * cal->disp[1]) / s;
        y = (sn * cal->disp[0] + c * cal->disp[1]) / s;
        if (isfinite(x) && isfinite(y)) {
            dir[0] = x;
            dir[1] = y;
        }
    }
    return s;
}

int rsm_odometry_cal_direction(const rsm_odometry_cal_t *cal, float dir[2])
{
    float d[2];
    if (cal == NULL || dir == NULL || !cal->have_ref) {
        return 0;
    }
    (void)span(cal, d);
    if (!isfinite(d[0])) {
        return 0; /* too short, an infinite span or a NaN reference */
    }
    dir[0] = d[0];
    dir[1] = d[1];
    return 1;
}

static float clamp_abs(float v, float most)
{
    return v < -most ? -most : (v > most ? most : v);
}

/* A scan whose position along odometry's way is known to at least this
 * share of the variance that way had without one (the last pinned scan's,
 * plus what odometry added since) pins the position there. */
#define CAL_PIN_SHARE 0.5f

/* The distance's equation: what matching found along odometry's
 * displacement s since the last pinned scan, less s, is k_scale * s. */
static void update_scale(rsm_odometry_cal_t *cal, const rsm_odometry_cal_config_t *cfg, const rsm_pose_t *est,
                         const float pos_cov[3])
{
    float dir[2];
    const float s = span(cal, dir);
    float before;
    float after;
    float e;
    if (s < CAL_MIN_DISP_M) {
        return; /* no way to measure along yet */
    }
    if (!(s <= CAL_MAX_TRAVEL_M) || !isfinite(dir[0])) {
        scale_reference(cal, est, pos_cov); /* a span no scan can measure (too long, inf, NaN) */
        return;
    }
    before = dir[0] * dir[0] * cal->sref_cov[0] + 2.0f * dir[0] * dir[1] * cal->sref_cov[1] +
             dir[1] * dir[1] * cal->sref_cov[2] + cal->disp_var;
    after = pos_cov != NULL ? dir[0] * dir[0] * pos_cov[0] + 2.0f * dir[0] * dir[1] * pos_cov[1] +
                                  dir[1] * dir[1] * pos_cov[2]
                            : before;
    if (!(after <= CAL_PIN_SHARE * before)) {
        return; /* unpinned: odometry's way goes on to the next pinned scan */
    }
    e = dir[0] * (est->x - cal->sref.x) + dir[1] * (est->y - cal->sref.y) - s;
    if (fabsf(e - cal->k_scale * s) <= cfg->gate_m + cfg->max_scale * s) {
        const float keep = 1.0f - 1.0f / cfg->memory;
        /* The span's error grows with its length as odometry's does
         * (weight 1/s): k is the distance found over the distance
         * driven, less one, and one long span weighs as its metres. */
        cal->scale_info = keep * cal->scale_info + s;
        cal->scale_moment = keep * cal->scale_moment + e;
        cal->k_scale = clamp_abs(cal->scale_moment / (cal->scale_info + cfg->scale_prior_m), cfg->max_scale);
        cal->scale_used++;
    }
    scale_reference(cal, est, pos_cov);
}

/* The heading's equation: the change found since the reference, less
 * odometry's turn t, is k_turn * t + k_drift * travel. */
static void update_heading(rsm_odometry_cal_t *cal, const rsm_odometry_cal_config_t *cfg, const rsm_pose_t *est,
                           float weight)
{
    const float t = cal->turn;
    const float d = cal->travel;
    float keep;
    float e;
    float a;
    float b;
    float c;
    float det;
    if (!(weight > 0.0f && weight <= 1.0f) || !(fabsf(t) <= RSM_PI) || !(fabsf(d) <= CAL_MAX_TRAVEL_M)) {
        return;
    }
    /* With |t| <= pi the change wraps as the turn does, but for a turn
     * near pi (gated out then). */
    e = rsm_wrap_angle(est->theta - cal->ref.theta) - t;
    if (!(fabsf(e - (cal->k_turn * t + cal->k_drift * d)) <= cfg->gate_rad)) {
        return;
    }
    keep = 1.0f - 1.0f / cfg->memory;
    cal->info[0] = keep * cal->info[0] + weight * t * t;
    cal->info[1] = keep * cal->info[1] + weight * t * d;
    cal->info[2] = keep * cal->info[2] + weight * d * d;
    cal->moment[0] = keep * cal->moment[0] + weight * t * e;
    cal->moment[1] = keep * cal->moment[1] + weight * d * e;
    /* The prior keeps the 2 x 2 system solvable (a robot that has only
     * driven straight says nothing about its turns) and the first scans'
     * correction small. */
    a = cal->info[0] + cfg->prior;
    b = cal->info[1];
    c = cal->info[2] + cfg->prior;
    det = a * c - b * b;
    if (det > 0.0f) {
        cal->k_turn = clamp_abs((c * cal->moment[0] - b * cal->moment[1]) / det, cfg->max_turn);
        cal->k_drift = clamp_abs((a * cal->moment[1] - b * cal->moment[0]) / det, cfg->max_drift);
        cal->used++;
    }
}

void rsm_odometry_cal_update(rsm_odometry_cal_t *cal, const rsm_odometry_cal_config_t *cfg, const rsm_pose_t *est,
                             float weight, const float pos_cov[3])
{
    if (cal == NULL || cfg == NULL || est == NULL) {
        return;
    }
    if (!cal->have_ref) {
        scale_reference(cal, est, pos_cov);
    } else if (cfg->memory > 0.0f) {
        if (scaling(cfg)) {
            update_scale(cal, cfg, est, pos_cov);
        }
        update_heading(cal, cfg, est, weight);
    }
    heading_reference(cal, est);
}
