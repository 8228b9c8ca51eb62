/* The C side of the Python module (port/python/rsm): a handful of plain
 * functions over one object that holds a localizer, its configuration and
 * a scan buffer, so that Python never lays out an rsm struct itself. It
 * allocates the object (rsmpy_size() bytes, aligned to rsmpy_align()),
 * names config fields by their paths in rsm_localizer_config_t (the names
 * rsm_localizer_config_check gives), and reads reports and counters as
 * flat arrays whose entries this file names. Built with the library's
 * sources into one shared object that ctypes loads (no Python.h). */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "rsm/localizer.h"
#include "rsm/status.h"

typedef struct rsmpy {
    rsm_localizer_config_t cfg; /* kept by pointer by loc: it lives beside it */
    rsm_localizer_t loc;
    rsm_scan_t scan;
    rsm_localizer_report_t rep;
} rsmpy_t;

/* What the Python side needs of a field: its kind decides how a value is
 * converted (a float, or a whole number from 0, or from INT32_MIN, to its
 * type's largest; enums are ints). */
enum { RSMPY_FLOAT = 0, RSMPY_UNSIGNED = 1, RSMPY_SIGNED = 2, RSMPY_ENUM = 3 };

typedef struct rsmpy_field {
    const char *name;
    size_t offset;
    size_t size;
    int kind;
    double top; /* enums: the largest value the header defines */
} rsmpy_field_t;

#define CFG_AT(field) offsetof(rsm_localizer_config_t, field), sizeof(((rsm_localizer_config_t *)0)->field)
#define FLT(field) {#field, CFG_AT(field), RSMPY_FLOAT, 0.0}
#define UNS(field) {#field, CFG_AT(field), RSMPY_UNSIGNED, 0.0}
#define SIG(field) {#field, CFG_AT(field), RSMPY_SIGNED, 0.0}
#define ENU(field, top) {#field, CFG_AT(field), RSMPY_ENUM, (double)(top)}

/* Every field of rsm_localizer_config_t but the timing hook, in the
 * header's order (tests/py/test_python_module.py checks it against the
 * headers). */
static const rsmpy_field_t fields[] = {
    ENU(method, RSM_METHOD_MAP),
    FLT(limits.min_range_m), FLT(limits.max_range_m),
    FLT(isolation.tol_m), FLT(isolation.slope), UNS(isolation.window), UNS(isolation.agree),
    UNS(occlusion.window), FLT(occlusion.span_m), FLT(occlusion.tol_m), FLT(occlusion.slope),
    FLT(occlusion.margin_m), FLT(occlusion.margin_rel),
    FLT(grid.cell_m), FLT(grid.sigma_m), ENU(grid.rule, RSM_GRID_NEAREST),
    SIG(harris.k_num), SIG(harris.k_den), SIG(harris.min_response), SIG(harris.nms_radius),
    FLT(ransac.inlier_tol_m), FLT(ransac.length_tol_m), FLT(ransac.min_pair_sep_m), FLT(ransac.confidence),
    UNS(ransac.max_iterations), UNS(ransac.min_support), UNS(ransac.seed),
    UNS(icp.max_iterations), FLT(icp.max_pair_dist_m), FLT(icp.converged_m), FLT(icp.converged_rad),
    UNS(icp.min_pairs),
    FLT(odometry.ticks_per_m_left), FLT(odometry.ticks_per_m_right), FLT(odometry.wheel_base_m),
    UNS(odometry.counter_bits), FLT(odometry.sigma_trans_per_m), FLT(odometry.sigma_rot_per_rad),
    FLT(odometry.sigma_rot_per_m), FLT(odometry.sigma_trans_min_m), FLT(odometry.sigma_rot_min_rad),
    FLT(odometry.max_wheel_speed_mps), FLT(odometry.max_turn_rate_rps), FLT(odometry.slack_s),
    FLT(odometry_cal.memory), FLT(odometry_cal.prior), FLT(odometry_cal.max_turn), FLT(odometry_cal.max_drift),
    FLT(odometry_cal.gate_rad), FLT(odometry_cal.max_scale), FLT(odometry_cal.gate_m),
    FLT(odometry_cal.scale_prior_m),
    FLT(laser_mount.x), FLT(laser_mount.y), FLT(laser_mount.theta), UNS(laser_upside_down),
    FLT(tmap.cell_m), UNS(tmap.levels), UNS(tmap.hit_inc), UNS(tmap.miss_dec), UNS(tmap.saturation),
    UNS(tmap.clear_margin), UNS(tmap.splat_from), UNS(tmap.age_shift), UNS(tmap.unconfirmed_shift),
    UNS(tmap.wall_level), UNS(tmap.wall_value), UNS(tmap.wall_echo), UNS(tmap.write_cells),
    UNS(mapmatch.iterations), FLT(mapmatch.sigma), FLT(mapmatch.min_step_m), FLT(mapmatch.min_step_rad),
    FLT(mapmatch.search_rad), FLT(mapmatch.search_step_rad), UNS(mapmatch.fan), FLT(mapmatch.gate_d2),
    FLT(mapmatch.basin), FLT(mapmatch.unpin_lo), FLT(mapmatch.unpin_hi),
    FLT(map_update_m), FLT(map_update_rad), FLT(recover_ratio), FLT(recover_m), FLT(recover_rad),
    FLT(recover_margin), UNS(recover_budget), FLT(refute_margin), FLT(conflict_max), FLT(doubt_m), FLT(doubt_rad),
    FLT(wall_sigma_rad), FLT(wall_window_rad), FLT(cov_floor_m), FLT(cov_floor_rad),
    UNS(global_budget), FLT(global_min_share), FLT(global_min_fit), FLT(global_crowded_fit), UNS(global_when_lost),
    UNS(map_frozen), UNS(map_loaded_hit), UNS(map_min_hits), UNS(map_on_reject), UNS(min_points), UNS(refuse_poor),
    FLT(track_min_fit), UNS(lost_scans), UNS(min_keypoints), FLT(match_window_m), FLT(search_sigmas),
    FLT(search_min_m), FLT(search_max_m), FLT(gate_d2), ENU(noise, RSM_NOISE_FIXED), FLT(r_min_xy_m),
    FLT(r_min_theta_rad), UNS(refine_iterations), UNS(refine_saturation), FLT(refine_noise_scale),
};

#define NFIELDS (sizeof fields / sizeof fields[0])

size_t rsmpy_size(void)
{
    return sizeof(rsmpy_t);
}

/* The strictest alignment a member may need (C99 has no alignof). */
size_t rsmpy_align(void)
{
    struct probe {
        char c;
        union {
            uint64_t u;
            double d;
            long double ld;
            void *p;
            void (*f)(void);
        } m;
    };
    return offsetof(struct probe, m);
}

size_t rsmpy_max_beams(void)
{
    return RSM_MAX_BEAMS;
}

/* The default configuration, the localizer not started. */
void rsmpy_reset(rsmpy_t *p)
{
    memset(p, 0, sizeof *p);
    p->cfg = rsm_localizer_config_default();
}

const char *rsmpy_field_name(size_t i)
{
    return i < NFIELDS ? fields[i].name : NULL;
}

int rsmpy_field_kind(size_t i)
{
    return i < NFIELDS ? fields[i].kind : -1;
}

static double field_top(const rsmpy_field_t *f)
{
    if (f->kind == RSMPY_ENUM) {
        return f->top;
    }
    return pow(2.0, (double)f->size * 8.0 - (f->kind == RSMPY_SIGNED ? 1.0 : 0.0)) - 1.0;
}

/* An integer field's bytes from and to a double: 1 and 2 bytes unsigned,
 * 4 bytes signed (int32_t, or an enum's int) or unsigned. */
static void int_put(unsigned char *at, const rsmpy_field_t *f, double v)
{
    if (f->size == 1u) {
        const uint8_t x = (uint8_t)v;
        memcpy(at, &x, sizeof x);
    } else if (f->size == 2u) {
        const uint16_t x = (uint16_t)v;
        memcpy(at, &x, sizeof x);
    } else if (f->kind != RSMPY_UNSIGNED) {
        const int32_t x = (int32_t)v;
        memcpy(at, &x, sizeof x);
    } else {
        const uint32_t x = (uint32_t)v;
        memcpy(at, &x, sizeof x);
    }
}

static double int_get(const unsigned char *at, const rsmpy_field_t *f)
{
    uint8_t u8;
    uint16_t u16;
    int32_t i32;
    uint32_t u32;
    if (f->size == 1u) {
        memcpy(&u8, at, sizeof u8);
        return (double)u8;
    }
    if (f->size == 2u) {
        memcpy(&u16, at, sizeof u16);
        return (double)u16;
    }
    if (f->kind != RSMPY_UNSIGNED) {
        memcpy(&i32, at, sizeof i32);
        return (double)i32;
    }
    memcpy(&u32, at, sizeof u32);
    return (double)u32;
}

/* Sets field i to v: 0; -1 no field i; -2 v is not a value of its type (a
 * float beyond FLT_MAX or not finite; an integer not whole or outside its
 * type or enum). The config is untouched on error. */
int rsmpy_config_set(rsmpy_t *p, size_t i, double v)
{
    const rsmpy_field_t *f;
    unsigned char *at;
    if (i >= NFIELDS) {
        return -1;
    }
    f = &fields[i];
    at = (unsigned char *)&p->cfg + f->offset;
    if (f->kind == RSMPY_FLOAT) {
        float x;
        if (!(fabs(v) <= 3.4028234663852886e38)) {
            return -2;
        }
        x = (float)v;
        memcpy(at, &x, sizeof x);
        return 0;
    }
    if (v != floor(v) || v > field_top(f) || v < (f->kind == RSMPY_SIGNED ? -field_top(f) - 1.0 : 0.0)) {
        return -2;
    }
    int_put(at, f, v);
    return 0;
}

/* Field i's value into *v: 0, or -1 (no field i). */
int rsmpy_config_get(const rsmpy_t *p, size_t i, double *v)
{
    const unsigned char *at;
    if (i >= NFIELDS) {
        return -1;
    }
    at = (const unsigned char *)&p->cfg + fields[i].offset;
    if (fields[i].kind == RSMPY_FLOAT) {
        float x;
        memcpy(&x, at, sizeof x);
        *v = (double)x;
    } else {
        *v = int_get(at, &fields[i]);
    }
    return 0;
}

/* Starts the localizer at (x, y, theta), theta wrapped, as rsm-nav does.
 * A configuration rsm_localizer_config_check refuses gives RSM_ERR_INVAL
 * with its field's name in *field; another RSM_ERR_INVAL (a start pose out
 * of range) leaves *field NULL. */
int rsmpy_init(rsmpy_t *p, double x, double y, double theta, const char **field)
{
    rsm_pose_t start;
    *field = NULL;
    if (rsm_localizer_config_check(&p->cfg, field) != RSM_OK) {
        return RSM_ERR_INVAL;
    }
    start.x = (float)x;
    start.y = (float)y;
    start.theta = rsm_wrap_angle((float)theta);
    return rsm_localizer_init(&p->loc, &p->cfg, &start, NULL);
}

int rsmpy_motion(rsmpy_t *p, float dx, float dy, float dtheta)
{
    rsm_motion_t u;
    u.dx = dx;
    u.dy = dy;
    u.dtheta = dtheta;
    return rsm_localizer_motion(&p->loc, &u);
}

int rsmpy_ticks(rsmpy_t *p, uint32_t left, uint32_t right)
{
    return rsm_localizer_ticks(&p->loc, left, right);
}

int rsmpy_set_pose(rsmpy_t *p, float x, float y, float theta)
{
    rsm_pose_t q;
    q.x = x;
    q.y = y;
    q.theta = theta;
    return rsm_localizer_set_pose(&p->loc, &q, NULL);
}

/* One scan of n readings: at angles[] when not NULL, else start + k * step
 * (rsm_scan_set_uniform). The report is kept for rsmpy_report. */
int rsmpy_scan(rsmpy_t *p, uint64_t stamp_us, size_t n, const float *ranges, const float *angles, float start,
               float step)
{
    int rc;
    if (n > RSM_MAX_BEAMS) {
        return RSM_ERR_NOMEM;
    }
    memcpy(p->scan.range_m, ranges, n * sizeof ranges[0]);
    if (angles != NULL) {
        memcpy(p->scan.angle_rad, angles, n * sizeof angles[0]);
        p->scan.count = n;
    } else if ((rc = rsm_scan_set_uniform(&p->scan, n, start, step)) != RSM_OK) {
        return rc;
    }
    p->scan.stamp_us = stamp_us;
    return rsm_localizer_scan(&p->loc, &p->scan, &p->rep);
}

/* The report's entries, each a name and its value (the enums as their
 * values), listed once for both. */
#define RSMPY_REPORT(X)                                                                                        \
    X(outcome, r->outcome) X(track, r->track) X(odometry, r->odometry) X(fit_ratio, r->fit_ratio)              \
    X(recovered, r->recovered) X(recovering, r->recovering) X(search_work, r->search_work)                     \
    X(x, r->pose.x) X(y, r->pose.y)                                                                            \
    X(theta, r->pose.theta) X(cov0, r->cov[0]) X(cov1, r->cov[1]) X(cov2, r->cov[2]) X(cov3, r->cov[3])        \
    X(cov4, r->cov[4]) X(cov5, r->cov[5]) X(cov6, r->cov[6]) X(cov7, r->cov[7]) X(cov8, r->cov[8])             \
    X(measured_x, r->measured.x) X(measured_y, r->measured.y) X(measured_theta, r->measured.theta)             \
    X(points, r->points) X(keypoints_cur, r->keypoints_cur) X(keypoints_ref, r->keypoints_ref)                 \
    X(matches, r->matches) X(inliers, r->inliers) X(iterations, r->iterations) X(residual_m, r->residual_m)    \
    X(mahalanobis_d2, r->mahalanobis_d2) X(crossing, r->crossing) X(unpinned, r->unpinned)

#define REPORT_NAME(name, value) #name,
static const char *const report_names[] = {RSMPY_REPORT(REPORT_NAME)};
#undef REPORT_NAME

#define NREPORT (sizeof report_names / sizeof report_names[0])

const char *rsmpy_report_name(size_t i)
{
    return i < NREPORT ? report_names[i] : NULL;
}

/* The last scan's report into out[NREPORT]. */
void rsmpy_report(const rsmpy_t *p, double *out)
{
    const rsm_localizer_report_t *r = &p->rep;
    size_t k = 0;
#define REPORT_VALUE(name, value) out[k++] = (double)(value);
    RSMPY_REPORT(REPORT_VALUE)
#undef REPORT_VALUE
}

/* The counters, each a uint32_t: a name and how many follow it (the
 * outcome and track arrays are one entry each, named per element by
 * rsm_outcome_name and rsm_track_name on the Python side). */
typedef struct rsmpy_counter {
    const char *name;
    size_t offset;
    size_t count;
} rsmpy_counter_t;

#define CNT(field) {#field, offsetof(rsm_localizer_counters_t, field), \
                    sizeof(((rsm_localizer_counters_t *)0)->field) / sizeof(uint32_t)}

static const rsmpy_counter_t counters[] = {
    CNT(scans), CNT(outcome), CNT(drops.nan), CNT(drops.too_short), CNT(drops.too_long), CNT(motions),
    CNT(bad_motions), CNT(searches), CNT(recovered), CNT(ambiguous), CNT(global_searches), CNT(global_found),
    CNT(global_ambiguous), CNT(global_work), CNT(caught_up), CNT(refuted), CNT(recounted), CNT(contradicted),
    CNT(track), CNT(unconfirmed), CNT(occluded), CNT(unpinned),
};

#define NCOUNTERS (sizeof counters / sizeof counters[0])

const char *rsmpy_counter_name(size_t i)
{
    return i < NCOUNTERS ? counters[i].name : NULL;
}

size_t rsmpy_counter_len(size_t i)
{
    return i < NCOUNTERS ? counters[i].count : 0u;
}

/* Every counter, the entries' elements one after another, into out (as
 * many as the lengths add up to). */
void rsmpy_counters(const rsmpy_t *p, uint32_t *out)
{
    size_t i;
    size_t k = 0;
    for (i = 0; i < NCOUNTERS; ++i) {
        memcpy(out + k, (const unsigned char *)&p->loc.counters + counters[i].offset,
               counters[i].count * sizeof(uint32_t));
        k += counters[i].count;
    }
}

/* The estimate and its covariance (row-major) now, after any motion. */
void rsmpy_pose(const rsmpy_t *p, double *pose, double *cov)
{
    const rsm_pose_t x = rsm_localizer_pose(&p->loc);
    float f[9];
    size_t c;
    pose[0] = (double)x.x;
    pose[1] = (double)x.y;
    pose[2] = (double)x.theta;
    (void)rsm_localizer_covariance(&p->loc, f);
    for (c = 0; c < 9u; ++c) {
        cov[c] = (double)f[c];
    }
}

int rsmpy_track(const rsmpy_t *p)
{
    return (int)rsm_localizer_track(&p->loc);
}

/* The last scan's usable readings in the robot frame, x then y per point,
 * at most cap points; returns how many there are. */
size_t rsmpy_scan_points(const rsmpy_t *p, float *xy, size_t cap)
{
    rsm_point_t pts[RSM_MAX_BEAMS];
    const size_t n = rsm_localizer_scan_points(&p->loc, pts, RSM_MAX_BEAMS);
    size_t k;
    for (k = 0; k < n && k < cap; ++k) {
        xy[2 * k] = pts[k].x;
        xy[2 * k + 1] = pts[k].y;
    }
    return n;
}

int rsmpy_map_bounds(const rsmpy_t *p, double *box)
{
    float b[4];
    const int rc = rsm_localizer_map_bounds(&p->loc, &b[0], &b[1], &b[2], &b[3]);
    size_t k;
    if (rc == RSM_OK) {
        for (k = 0; k < 4u; ++k) {
            box[k] = (double)b[k];
        }
    }
    return rc;
}

/* The persistent map's occupancy at the centres of a w x h raster of
 * cells of side cell from (x0, y0): out[j * w + i] at x0 + (i + 0.5) cell,
 * y0 + (j + 0.5) cell (row 0 at y0). */
int rsmpy_map_raster(const rsmpy_t *p, double x0, double y0, double cell, size_t w, size_t h, float *out)
{
    size_t i;
    size_t j;
    for (j = 0; j < h; ++j) {
        const float y = (float)(y0 + ((double)j + 0.5) * cell);
        for (i = 0; i < w; ++i) {
            const float x = (float)(x0 + ((double)i + 0.5) * cell);
            const int rc = rsm_localizer_map_occupancy(&p->loc, x, y, &out[j * w + i]);
            if (rc != RSM_OK) {
                return rc;
            }
        }
    }
    return RSM_OK;
}
