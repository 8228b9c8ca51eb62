/* Differential-drive odometry: encoder tick deltas (or pose deltas from a log)
 * to a motion increment, its noise, and the motion-model Jacobians.
 *
 * Motion increment u = (dx, dy, dtheta) is expressed in the robot frame at
 * the start of the step; the new pose is pose (+) u. From wheel travel
 * dL, dR (metres): dS = (dL + dR) / 2, dtheta = (dR - dL) / B (CCW positive;
 * the paper's eq. 5 has a stray 1/2 and the opposite sign), and the chord of
 * the arc is taken at the mid heading: dx = dS cos(dtheta/2),
 * dy = dS sin(dtheta/2). */
#ifndef RSM_ODOMETRY_H
#define RSM_ODOMETRY_H

#include <stdint.h>

#include "rsm/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct rsm_odometry_config {
    float ticks_per_m_left;   /* encoder ticks per metre of tyre travel (TicksMM * 1000) */
    float ticks_per_m_right;
    float wheel_base_m;       /* B: effective track width, metres */
    uint8_t counter_bits;     /* width of the hardware counters: 16..32 (32 for ARIA ENCODER) */
    /* Process noise (standard deviations) of the increment: */
    float sigma_trans_per_m;  /* m of translation error per m travelled */
    float sigma_rot_per_rad;  /* rad of heading error per rad turned */
    float sigma_rot_per_m;    /* rad of heading error per m travelled (drift) */
    float sigma_trans_min_m;  /* floor on translation std per step */
    float sigma_rot_min_rad;  /* floor on heading std per step */
    /* Plausibility of a tick increment (0 = that check off). A step whose
     * wheel travel or turn exceeds what these rates allow in the elapsed time
     * plus slack_s is refused and counted: a corrupt packet that passed its
     * checksum, or counters that started over. */
    float max_wheel_speed_mps; /* fastest plausible wheel, m/s */
    float max_turn_rate_rps;   /* fastest plausible turn, rad/s */
    float slack_s;             /* added to every step's elapsed time (stamp jitter, and the
                                * whole allowance when the caller gives no time), s */
} rsm_odometry_config_t;

/* P3-DX defaults: TicksMM 128 (calibrate), B = 0.357 m, 32-bit counters.
 * Noise: 0.05 m/m, 0.05 rad/rad, 0.02 rad/m, floors 2 mm and 2 mrad.
 * Plausibility: 3 m/s per wheel, 4 pi rad/s (two turns a second), 1 s of
 * slack: far beyond what a robot of this class does, so only corrupt or
 * restarted counts are refused (one step without a time may move up to
 * 3 m and turn up to 2 turns). */
rsm_odometry_config_t rsm_odometry_config_default(void);

/* One reading of the wheel encoders, as it travels from a driver through the
 * aligner (rsm/sync.h) to the odometry: free-running counters (only the low
 * counter_bits count; differences are taken modulo 2^counter_bits, see
 * rsm_odometry_count_delta) and the time they were read. */
typedef struct rsm_odometry_sample {
    uint64_t stamp_us;        /* clock time of the reading */
    uint32_t left;            /* left wheel counter, ticks */
    uint32_t right;           /* right wheel counter, ticks */
} rsm_odometry_sample_t;

typedef struct rsm_odometry {
    rsm_odometry_config_t cfg; /* a copy: rsm_odometry_set_config changes it at run time */
    uint32_t last_left;
    uint32_t last_right;
    uint8_t have_last;
    uint8_t have_time;        /* last_us is known */
    uint64_t last_us;
    /* A refused sample, kept: if the next one follows on from it, the
     * counters started over there (a robot restarted) and it becomes the
     * baseline; if the next follows on from the last accepted one, it was a
     * one-off corrupt packet and nothing is lost. */
    uint8_t have_cand;
    uint8_t cand_has_time;
    uint32_t cand_left;
    uint32_t cand_right;
    uint64_t cand_us;
    uint32_t steps;           /* increments produced */
    uint32_t implausible;     /* samples refused as beyond the plausible speed or turn rate */
    uint32_t relatched;       /* times the counters were taken up again from a refused sample */
} rsm_odometry_t;

/* rsm_odometry_update_ticks_at without a time. */
#define RSM_ODOMETRY_NO_TIME UINT64_MAX

typedef struct rsm_motion {
    float dx;       /* m, robot frame at step start */
    float dy;       /* m */
    float dtheta;   /* rad, wrapped to (-pi, pi] */
} rsm_motion_t;

/* RSM_OK if cfg is usable (positive, finite geometry; 16 <= counter_bits
 * <= 32; non-negative, finite noise and plausibility figures), else
 * RSM_ERR_INVAL with the first bad field's name ("odometry.wheel_base_m",
 * a static string) in *field when field is not NULL. Reads only. */
int rsm_odometry_config_check(const rsm_odometry_config_t *cfg, const char **field);

/* Validates cfg (positive geometry, 16 <= counter_bits <= 32, non-negative
 * noise), copies it (the caller's struct is free on return) and resets the
 * state. Returns RSM_OK or RSM_ERR_INVAL (odo unchanged). */
int rsm_odometry_init(rsm_odometry_t *odo, const rsm_odometry_config_t *cfg);

/* Replaces the configuration at run time (a robot's calibration read after
 * start-up), validated as rsm_odometry_init does and copied. The baseline
 * counts and the counters are kept, so the next sample's increment is
 * converted with the new geometry; a new counter_bits restarts the counts
 * (the next sample only latches). Returns RSM_OK or RSM_ERR_INVAL (odo
 * unchanged). */
int rsm_odometry_set_config(rsm_odometry_t *odo, const rsm_odometry_config_t *cfg);

/* to - from of two counters counter_bits wide (16..32; others read as 32),
 * taken modulo 2^bits and read as a two's-complement number of that width:
 * a counter that wrapped forwards gives a small positive step, one that
 * wrapped backwards a small negative one (-2^(bits-1) for half a turn of
 * the counter). The one place counter wrap-around is handled. Pure. */
int32_t rsm_odometry_count_delta(uint32_t to, uint32_t from, uint8_t bits);

/* Feeds raw counter values (only the low counter_bits are used). The first
 * call only latches the counts and returns RSM_ERR_AGAIN with *out zeroed;
 * later calls return RSM_OK and the increment since the previous call, with
 * differences taken modulo 2^counter_bits (wrap-around safe). An
 * implausible increment (see the config) gives RSM_ERR_RANGE with *out
 * zeroed, counted in implausible; the baseline stays, unless the next
 * sample follows on from the refused one (counters that started over:
 * counted in relatched). Without a time the step is allowed slack_s. */
int rsm_odometry_update_ticks(rsm_odometry_t *odo, uint32_t left, uint32_t right, rsm_motion_t *out);

/* The same with the time the counters were read (any microsecond clock;
 * RSM_ODOMETRY_NO_TIME if unknown): the plausible step grows with the time
 * since the baseline. */
int rsm_odometry_update_ticks_at(rsm_odometry_t *odo, uint32_t left, uint32_t right, uint64_t stamp_us,
                                 rsm_motion_t *out);

/* The counters start over (a new connection): the next sample only
 * latches. */
void rsm_odometry_restart(rsm_odometry_t *odo);

/* Increment from signed tick differences already computed by the caller
 * (zero increment if cfg is NULL or has non-positive geometry). */
rsm_motion_t rsm_odometry_from_ticks(const rsm_odometry_config_t *cfg, int32_t d_left, int32_t d_right);

/* Increment between two odometry poses from a log: between(prev, cur). */
rsm_motion_t rsm_odometry_from_poses(const rsm_pose_t *prev, const rsm_pose_t *cur);

/* Applies an increment: returns pose (+) u. */
rsm_pose_t rsm_odometry_apply(const rsm_pose_t *pose, const rsm_motion_t *u);

/* Jacobians of pose (+) u at (pose, u): jv = d/d(pose), ju = d/d(u), both
 * 3x3 row-major. */
void rsm_odometry_jacobians(const rsm_pose_t *pose, const rsm_motion_t *u, float jv[9], float ju[9]);

/* Diagonal process noise covariance Q (3x3 row-major, in increment space)
 * that grows with |dS| and |dtheta| per the config, with |dS| taken as the
 * chord |(dx, dy)|:
 *   var_dx = var_dy = (sigma_trans_per_m |dS|)^2 + sigma_trans_min_m^2
 *   var_dtheta = (sigma_rot_per_rad |dtheta|)^2 + (sigma_rot_per_m |dS|)^2
 *                + sigma_rot_min_rad^2
 * Translation noise is isotropic in the step frame. q untouched if any
 * argument is NULL. */
void rsm_odometry_noise(const rsm_odometry_config_t *cfg, const rsm_motion_t *u, float q[9]);

/* The same for a step that odometry reported late, in one piece (scans
 * missing for seconds, the motion since the last one counted at once): its
 * distance was driven as ordinary steps of at most RSM_ODOMETRY_WALK_STEP_M,
 * whose errors add up as a walk, so beyond that length the distance terms'
 * variance grows linearly with |dS|, not as its square, and the heading's
 * walk along the step moves the position across it:
 *   along the chord: sigma_trans_per_m^2 |dS| w + sigma_trans_min_m^2
 *   across it: the same + sigma_rot_per_m^2 w |dS|^3 / 3
 *   var_dtheta = (sigma_rot_per_rad |dtheta|)^2 + sigma_rot_per_m^2 |dS| w
 *                + sigma_rot_min_rad^2,    w = min(|dS|, RSM_ODOMETRY_WALK_STEP_M)
 *   across with dtheta: sigma_rot_per_m^2 w |dS|^2 / 2
 * (what the filter carries from step to step when the same drive comes in
 * steps of w). The turn's term stays a square: a wheel base off its
 * nominal misjudges every turn by the same share. Up to that length it
 * equals rsm_odometry_noise. */
#define RSM_ODOMETRY_WALK_STEP_M 0.4f
void rsm_odometry_noise_walk(const rsm_odometry_config_t *cfg, const rsm_motion_t *u, float q[9]);

/* ---- calibration of odometry's systematic heading and distance errors ---
 *
 * Wheel odometry turns by a share too much or too little (a wheel base off
 * its nominal, tyres that slip in turns) and drifts to one side as it
 * drives (wheels of slightly different sizes). Both are the same from one
 * minute to the next, unlike the noise, and a scan matcher that leans on
 * odometry's prediction leans that way every scan: wherever the scans pin
 * the heading less (new ground, a scan full of outliers) the error adds up.
 * The calibration fits the heading change that matching found between two
 * scans to odometry's turn and forward travel over the same steps,
 *     found - turn = k_turn * turn + k_drift * travel,
 * by least squares with old scans fading. Wheels of a size off their
 * nominal also measure every distance a share too long or too short; where
 * the scans pin nothing along the robot's way (a bare corridor) the
 * estimate there is odometry's, so that share is the drift. The distance
 * matching found along odometry's displacement s is fitted the same way,
 *     found - s = k_scale * s,
 * between scans that pin the position along the way (the scans between
 * them, unpinned, carry odometry's error, which the next pinned one takes
 * back: an equation per scan would count that as the error). Each later
 * increment is corrected:
 *     dtheta' = dtheta * (1 + k_turn) + k_drift * dx,
 *     (dx', dy') = (dx, dy) * (1 + k_scale). */
typedef struct rsm_odometry_cal_config {
    float memory;    /* scans over which the evidence fades (each weighs 1 - 1/memory of the
                      * last); 0 = off, else >= 2; default 1024 */
    float prior;     /* evidence for no correction before any scan, in rad^2 of turn and m^2
                      * of travel (a turn of 0.1 rad is 0.01); > 0; default 0.01 */
    float max_turn;  /* |k_turn| at most (a share); in (0, 1); default 0.25 */
    float max_drift; /* |k_drift| at most, rad per metre; > 0; default 0.1 */
    float gate_rad;  /* a scan whose heading change the correction misses by more than this
                      * (a slip, a wrong match) is left out; > 0; default 0.1 */
    float max_scale; /* |k_scale| at most (a share of the distance); 0 = distance not
                      * calibrated, else in (0, 1); default 0 (off: with many outliers
                      * it costs more than it gains, docs/map.md); 0.1 turns it on */
    float gate_m;    /* a scan whose distance along odometry's travel the correction misses
                      * by more than this is left out of the distance's fit; > 0; default 0.05 */
    float scale_prior_m; /* evidence for no distance correction before any scan, in metres
                      * driven between pinned scans; > 0; default 1 */
} rsm_odometry_cal_config_t;

typedef struct rsm_odometry_cal {
    float info[3];    /* fading sums of w (turn, travel)^T (turn, travel): tt, td, dd */
    float moment[2];  /* ... and of w (turn, travel) * (found - turn) */
    float scale_info; /* fading sums of s and (found - s), s odometry's distance */
    float scale_moment;
    float k_turn;     /* the correction in force */
    float k_drift;
    float k_scale;
    float turn;       /* odometry's raw turn and forward travel since the reference */
    float travel;
    float disp[2];    /* odometry's displacement since the distance's reference, in its frame,
                       * its corrected turn and the variance it added since then (m^2) */
    float disp_turn;
    float disp_var;
    rsm_pose_t sref;  /* the estimate at the last scan that pinned the position along the way */
    float sref_cov[3]; /* ... and its position's covariance there: xx, xy, yy */
    rsm_pose_t ref;   /* the estimate at the reference scan */
    uint8_t have_ref;
    uint32_t used;    /* scans that updated the heading's correction */
    uint32_t scale_used; /* ... and the distance's */
} rsm_odometry_cal_t;

rsm_odometry_cal_config_t rsm_odometry_cal_config_default(void);

/* RSM_OK if cfg is usable (see the fields; with memory 0 the others are
 * not looked at), else RSM_ERR_INVAL with the first bad field's name
 * ("odometry_cal.memory", a static string) in *field when field is not
 * NULL. Reads only. */
int rsm_odometry_cal_config_check(const rsm_odometry_cal_config_t *cfg, const char **field);

/* No correction, no evidence, no reference. Nothing if cal is NULL. */
void rsm_odometry_cal_init(rsm_odometry_cal_t *cal);

/* u corrected by the correction in force; u as it is if cal is NULL or u
 * is longer than 10 m (a step over a gap in the scans, whose path the
 * correction would need). Pure: rsm_odometry_cal_count counts u once it is
 * used. */
rsm_motion_t rsm_odometry_cal_apply(const rsm_odometry_cal_t *cal, const rsm_motion_t *u);

/* Counts the raw increment u towards the next update (call it for each
 * increment the prediction took, and only then), with the variance var_t
 * (m^2) the prediction added to the position for it; the distance's part
 * only when cfg calibrates the distance (max_scale > 0). Nothing if an
 * argument is NULL. */
void rsm_odometry_cal_count(rsm_odometry_cal_t *cal, const rsm_odometry_cal_config_t *cfg, const rsm_motion_t *u,
                            float var_t);

/* Makes est the reference the next update measures from, the heading's
 * and the distance's (the first scan, or one whose estimate jumped: a
 * recovery), and restarts the sums since the reference. */
void rsm_odometry_cal_reference(rsm_odometry_cal_t *cal, const rsm_pose_t *est);

/* A scan matched at est: the heading change since the reference, less
 * odometry's raw turn, is one more equation, weighted by weight (the
 * share of the heading's variance the scan removed, 0..1; 0 adds
 * nothing), unless it misses the correction in force by more than
 * gate_rad (a NaN heading always does) or odometry's sums are beyond any
 * step between two scans (a turn over pi, travel over 10 m; a corrupt
 * increment): the correction in force then stays. Then est becomes the
 * reference. pos_cov is the covariance of est's position (xx, xy, yy;
 * NULL: unknown). When the variance along odometry's displacement since
 * the distance's reference is at most half of what it was there plus what
 * odometry added since, the scan pins the position along the way: the
 * distance found along that displacement is one more equation for k_scale
 * (gated by gate_m plus max_scale of the distance; none when max_scale is
 * 0) and est the distance's reference. A span over 10 m, or one no
 * direction can be taken of, only restarts it.
 * Without a reference it only takes est as one. */
void rsm_odometry_cal_update(rsm_odometry_cal_t *cal, const rsm_odometry_cal_config_t *cfg, const rsm_pose_t *est,
                             float weight, const float pos_cov[3]);

/* The unit direction, in the world frame, of odometry's displacement since
 * the distance's reference (what pinning is judged along), in dir; 0 and
 * dir untouched without a reference, a displacement of 1 mm at least or a
 * finite direction. */
int rsm_odometry_cal_direction(const rsm_odometry_cal_t *cal, float dir[2]);

#ifdef __cplusplus
}
#endif

#endif /* RSM_ODOMETRY_H */
