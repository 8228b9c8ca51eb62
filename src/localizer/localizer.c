#include "rsm/localizer.h"

#include <math.h>
#include <string.h>

#include "rsm/status.h"
#include "core/bits.h"
#include "core/check.h"
#include "core/ekf.h"
#include "core/fmath.h"
#include "core/grid.h"
#include "paper/harris.h"
#include "paper/icp.h"
#include "paper/map.h"
#include "map/mapstate.h"
#include "map/globalsearch.h"
#include "map/mapmatch.h"
#include "paper/match.h"
#include "paper/ransac.h"
#include "map/tilemap.h"
#include "localizer/wallgrid.h"

rsm_localizer_config_t rsm_localizer_config_default(void)
{
    rsm_localizer_config_t c;
    memset(&c, 0, sizeof c);
    c.method = RSM_METHOD_MAP;
    c.limits = rsm_scan_limits_default();
    c.grid = rsm_grid_config_default();
    c.harris = rsm_harris_config_default();
    c.ransac = rsm_ransac_config_default();
    c.icp = rsm_icp_config_default();
    c.odometry = rsm_odometry_config_default();
    /* Measured on the Intel and ACES logs (tools/bench): heading drift
     * dominates, and heading errors grow with turning faster than the
     * generic 5 % (fast turns). */
    c.odometry.sigma_rot_per_m = 0.2f;
    c.odometry.sigma_rot_per_rad = 0.1f;
    c.map_frozen = 0u;
    c.map_loaded_hit = 1u;
    c.global_budget = 45000u;
    c.global_min_share = 0.8f;
    c.global_min_fit = 0.8f;
    c.global_crowded_fit = 0.9f;
    c.global_when_lost = 0u;
    c.map_min_hits = 1u;
    c.map_on_reject = 1u;
    c.min_points = 20u;
    c.lost_scans = 10u;
    c.refuse_poor = 1u;
    c.min_keypoints = 4u;
    c.match_window_m = 0.05f;
    c.search_sigmas = 3.0f;
    c.search_min_m = 0.15f;
    c.search_max_m = 0.6f;
    c.gate_d2 = 16.27f;
    c.noise = RSM_NOISE_RESIDUAL;
    c.r_min_xy_m = 0.003f;
    c.r_min_theta_rad = 0.001f;
    c.refine_iterations = 10u;
    c.refine_saturation = 2u;
    c.refine_noise_scale = 10.0f;
    c.laser_mount.x = 0.0f;
    c.laser_mount.y = 0.0f;
    c.laser_mount.theta = 0.0f;
    c.laser_upside_down = 0u;
    c.tmap = rsm_tmap_config_default();
    c.mapmatch = rsm_mapmatch_config_default();
    c.map_update_m = 0.4f;
    c.map_update_rad = 0.5f;
    c.recover_ratio = 0.4f;
    c.recover_m = 1.0f;
    c.recover_rad = 0.3f;
    c.recover_margin = 0.1f;
    c.recover_budget = 0u;
    c.refute_margin = 0.1f;
    c.track_min_fit = 0.7f;
    c.conflict_max = 0.5f;
    c.doubt_m = 0.1f;
    c.doubt_rad = 0.1f;
    c.wall_sigma_rad = 0.0015f;
    c.wall_window_rad = 0.035f;
    c.cov_floor_m = 0.008f;
    c.cov_floor_rad = 0.002f;
    c.isolation.tol_m = 0.0f;
    c.isolation.slope = 3.0f;
    c.isolation.window = 2u;
    c.isolation.agree = 1u;
    /* A laser cannot see through a wall: a return behind two neighbours
     * that span its beam is a phantom (docs/map.md, "Outliers"). */
    c.occlusion.window = 2u;
    c.occlusion.span_m = 0.3f;
    c.occlusion.tol_m = 0.1f;
    c.occlusion.slope = 3.0f;
    c.occlusion.margin_m = 0.2f;
    c.occlusion.margin_rel = 0.05f;
    c.odometry_cal = rsm_odometry_cal_config_default();
    c.clock_fn = NULL;
    c.clock_ctx = NULL;
    return c;
}

const char *rsm_outcome_name(rsm_outcome_t o)
{
    switch (o) {
    case RSM_SCAN_ACCEPTED: return "accepted";
    case RSM_SCAN_FIRST: return "first";
    case RSM_SCAN_ODOMETRY: return "odometry";
    case RSM_SCAN_FEW_POINTS: return "few_points";
    case RSM_SCAN_FEW_KEYPOINTS: return "few_keypoints";
    case RSM_SCAN_FEW_MATCHES: return "few_matches";
    case RSM_SCAN_LOW_SUPPORT: return "low_support";
    case RSM_SCAN_JUMP: return "jump";
    case RSM_SCAN_FILTER: return "filter";
    case RSM_SCAN_OUT_OF_ORDER: return "out_of_order";
    case RSM_SCAN_POOR_FIT: return "poor_fit";
    case RSM_SCAN_SEARCHING: return "searching";
    default: return "unknown";
    }
}

const char *rsm_odometry_verdict_name(rsm_odometry_verdict_t v)
{
    switch (v) {
    case RSM_ODOMETRY_TRUSTED: return "trusted";
    case RSM_ODOMETRY_CAUGHT_UP: return "caught_up";
    case RSM_ODOMETRY_REFUTED: return "refuted";
    case RSM_ODOMETRY_RECOUNTED: return "recounted";
    default: return "unknown";
    }
}

const char *rsm_track_name(rsm_track_t t)
{
    switch (t) {
    case RSM_TRACK_TRACKING: return "tracking";
    case RSM_TRACK_UNCERTAIN: return "uncertain";
    case RSM_TRACK_LOST: return "lost";
    default: return "unknown";
    }
}

rsm_track_t rsm_localizer_track(const rsm_localizer_t *loc)
{
    return rsm_localizer_ready(loc) ? loc->last.track : RSM_TRACK_LOST;
}

const char *rsm_stage_name(rsm_stage_t s)
{
    switch (s) {
    case RSM_STAGE_POINTS: return "points";
    case RSM_STAGE_GRID: return "grid";
    case RSM_STAGE_HARRIS: return "harris";
    case RSM_STAGE_MATCH: return "match";
    case RSM_STAGE_RANSAC: return "ransac";
    case RSM_STAGE_REFINE: return "refine";
    case RSM_STAGE_ICP: return "icp";
    case RSM_STAGE_EKF: return "ekf";
    case RSM_STAGE_MAP: return "map";
    case RSM_STAGE_MAPMATCH: return "mapmatch";
    default: return "unknown";
    }
}

/* The optional timing hook, on the stack of one rsm_localizer_scan call:
 * the stage running now and the clock reading when it started. Without a
 * clock_fn every operation is a single test. */
typedef struct stage_clock {
    uint32_t (*fn)(void *ctx);
    void *ctx;
    uint32_t start;
    uint32_t last;
    rsm_stage_t stage;
    rsm_localizer_report_t *rep;
} stage_clock_t;

static void stage_begin(stage_clock_t *c, const rsm_localizer_config_t *cfg, rsm_localizer_report_t *rep)
{
    c->fn = cfg->clock_fn;
    c->ctx = cfg->clock_ctx;
    c->rep = rep;
    c->stage = RSM_STAGE_POINTS;
    c->start = 0u;
    c->last = 0u;
    if (c->fn != NULL) {
        c->start = c->fn(c->ctx);
        c->last = c->start;
    }
}

/* Charges the time since the last switch to the running stage and starts s. */
static void stage_switch(stage_clock_t *c, rsm_stage_t s)
{
    if (c->fn != NULL) {
        const uint32_t now = c->fn(c->ctx);
        c->rep->stage_time[c->stage] += now - c->last;
        c->last = now;
    }
    c->stage = s;
}

/* Charges the running stage and the whole call. */
static void stage_end(stage_clock_t *c)
{
    if (c->fn != NULL) {
        const uint32_t now = c->fn(c->ctx);
        c->rep->stage_time[c->stage] += now - c->last;
        c->rep->step_time = now - c->start;
        c->last = now;
    }
}

int rsm_localizer_init_checked(rsm_localizer_t *loc, size_t loc_size, unsigned long fingerprint,
                               const rsm_localizer_config_t *cfg, const rsm_pose_t *x0, const float p0[9])
{
    int rc;
    if (loc_size != sizeof(rsm_localizer_t) || fingerprint != (unsigned long)RSM_CONFIG_FINGERPRINT) {
        return RSM_ERR_CONFIG;
    }
    /* Every part of cfg is checked before anything is written (the
     * field is named by rsm_localizer_config_check, src/localizer/localizer_check.c). */
    if (loc == NULL || x0 == NULL || rsm_localizer_config_check(cfg, NULL) != RSM_OK) {
        return RSM_ERR_INVAL;
    }
    memset(loc, 0, sizeof *loc);
    loc->cfg = cfg;
    rsm_scan_trig_init(&loc->trig);
    rsm_odometry_cal_init(&loc->odo_cal);
    if ((rc = rsm_ekf_init(&loc->ekf, x0, p0)) != RSM_OK || (rc = rsm_odometry_init(&loc->odo, &cfg->odometry)) != RSM_OK) {
        return rc;
    }
    /* Each method initialises only its own member of the state union. */
    switch (cfg->method) {
    case RSM_METHOD_PAPER:
        if ((rc = rsm_ransac_init(&loc->state.paper.ransac, &cfg->ransac)) != RSM_OK ||
            (rc = rsm_map_init(&loc->state.paper.map, cfg->grid.cell_m, x0->x, x0->y)) != RSM_OK) {
            return rc;
        }
        rsm_image_reset(&loc->state.paper.image);
        break;
    case RSM_METHOD_ICP:
        rc = rsm_icp_init(&loc->state.icp, &cfg->icp);
        break;
    case RSM_METHOD_MAP:
        rc = rsm_tmap_init(&loc->state.persistent.map, &cfg->tmap);
        loc->state.persistent.written = *x0;
        loc->state.persistent.anchor = *x0;
        loc->state.persistent.trusted = *x0;
        break;
    default:
        break;
    }
    if (rc == RSM_OK) {
        loc->magic = (uint32_t)RSM_LOCALIZER_MAGIC;
    }
    return rc;
}

int rsm_localizer_ready(const rsm_localizer_t *loc)
{
    return loc != NULL && loc->magic == (uint32_t)RSM_LOCALIZER_MAGIC && loc->cfg != NULL;
}

static int ready(const rsm_localizer_t *loc)
{
    return rsm_localizer_ready(loc);
}

/* A global search is under way (RSM_METHOD_MAP). */
static int global_running(const rsm_localizer_t *loc)
{
    return loc->cfg->method == RSM_METHOD_MAP && loc->state.persistent.global.phase != RSM_GLOBAL_IDLE;
}

/* The recovery's phases (rsm_recovery_t.phase). Resting: one ended
 * without a pose, and none begins again until the robot has moved to a new
 * view (PROVE_AGAIN_M, PROVE_AGAIN_RAD from base): the same view would
 * prove nothing again, and the scans that begin one are not written. */
enum {
    RECOVER_IDLE = 0,
    RECOVER_SEARCHING = 1,
    RECOVER_DESCENDING = 2,
    RECOVER_PROVING = 3,
    RECOVER_TAKING = 4,
    RECOVER_RESTING = 5
};

/* The global search's grid memory: the caller's (rsm_localizer_set_search_memory),
 * else that of the scan a map write reads, idle during a search. */
static uint8_t *search_grid(rsm_localizer_t *loc)
{
    return loc->state.persistent.search_mem != NULL ? loc->state.persistent.search_mem : loc->frame.global_grid;
}

static size_t search_bytes(const rsm_localizer_t *loc)
{
    return loc->state.persistent.search_mem != NULL ? (size_t)loc->state.persistent.search_bytes
                                                    : sizeof loc->frame.global_grid;
}

void rsm_localizer_map_cleared(rsm_localizer_t *loc)
{
    loc->state.persistent.global.cached = 0u;
    loc->state.persistent.global.taken_back = 0u;
}

void rsm_localizer_map_replaced(rsm_localizer_t *loc, float fit)
{
    loc->have_scan = 1u;
    loc->state.persistent.written = loc->ekf.x;
    loc->state.persistent.fit = fit;
    loc->state.persistent.map_fit = fit;
    rsm_localizer_map_cleared(loc);
    loc->state.persistent.recovery.phase = RECOVER_IDLE;
    /* Written at a loaded map's rate from now on (map_loaded_hit). */
    loc->state.persistent.map.write_hit = loc->cfg->map_loaded_hit > 0u ? loc->cfg->map_loaded_hit
                                                                         : loc->state.persistent.map.cfg.hit_inc;
    /* Another map, another grid: learnt again from the scans tracking in it. */
    loc->state.persistent.wall_c = 0.0f;
    loc->state.persistent.wall_s = 0.0f;
    loc->state.persistent.wall_scans = 0u;
    /* The global search's grids, built now while nothing else runs (they
     * take the memory of a map write's scan, idle after a load or an
     * import): a search in the map as it came, frozen or before its first
     * write, begins without paying for them out of its scans' budget. A
     * map the search cannot take (RSM_ERR_NOMEM) is kept: tracking needs
     * none. */
    if (loc->cfg->method == RSM_METHOD_MAP) {
        (void)rsm_global_prepare(&loc->state.persistent.global, search_grid(loc), search_bytes(loc),
                                 &loc->state.persistent.map, NULL);
    }
    if (global_running(loc)) {
        loc->state.persistent.global.phase = RSM_GLOBAL_PENDING;
    }
    /* A winner waiting for a second proof was found in the map before. */
    loc->state.persistent.global.pending = 0u;
}

int rsm_localizer_set_pose(rsm_localizer_t *loc, const rsm_pose_t *x, const float p[9])
{
    static const rsm_pose_t none = {0.0f, 0.0f, 0.0f};
    rsm_ekf_t ekf;
    if (!ready(loc) || x == NULL || rsm_ekf_init(&ekf, x, p) != RSM_OK) {
        return RSM_ERR_INVAL;
    }
    /* Only the estimate: the filter's counters stay. */
    loc->ekf.x = ekf.x;
    memcpy(loc->ekf.p, ekf.p, sizeof loc->ekf.p);
    if (loc->cfg->method == RSM_METHOD_MAP) {
        loc->state.persistent.anchor = ekf.x;
        loc->state.persistent.trusted = ekf.x;
        loc->state.persistent.since = none;
        loc->state.persistent.last_step = none;
        loc->state.persistent.recovery.phase = RECOVER_IDLE;
    }
    loc->poor_run = 0u;
    loc->last.track = RSM_TRACK_TRACKING;
    loc->last.pose = ekf.x;
    return RSM_OK;
}

/* Whether odometry's heading (and distance) is calibrated from the matches. */
static int calibrating(const rsm_localizer_t *loc)
{
    return loc->cfg->method == RSM_METHOD_MAP && loc->cfg->odometry_cal.memory > 0.0f;
}

/* The walk's covariance (walk_p) carried over step v from before (the
 * filter before the step). It is the filter's own until a step since the
 * last scan is longer than RSM_ODOMETRY_WALK_STEP_M (walk_apart), and is
 * only kept from then on: ordinary steps cost nothing more. */
static void walk(rsm_localizer_t *loc, const rsm_motion_t *v, rsm_ekf_t *before)
{
    float qw[9];
    if (loc->counters.motions == loc->motions_at_scan || !loc->have_scan) {
        loc->state.persistent.walk_apart = 0u;
    }
    if (loc->state.persistent.walk_apart) {
        memcpy(before->p, loc->state.persistent.walk_p, sizeof before->p);
    } else if (v->dx * v->dx + v->dy * v->dy <= RSM_ODOMETRY_WALK_STEP_M * RSM_ODOMETRY_WALK_STEP_M) {
        return;
    }
    rsm_odometry_noise_walk(&loc->odo.cfg, v, qw);
    if (rsm_ekf_predict(before, v, loc->have_scan ? qw : NULL) == RSM_OK) {
        memcpy(loc->state.persistent.walk_p, before->p, sizeof loc->state.persistent.walk_p);
    } else {
        memcpy(loc->state.persistent.walk_p, loc->ekf.p, sizeof loc->state.persistent.walk_p);
    }
    loc->state.persistent.walk_apart = 1u;
}

int rsm_localizer_motion(rsm_localizer_t *loc, const rsm_motion_t *u)
{
    float q[9];
    rsm_ekf_t before;
    rsm_motion_t v;
    if (!ready(loc) || u == NULL) {
        return RSM_ERR_INVAL;
    }
    if (!isfinite(u->dx) || !isfinite(u->dy) || !isfinite(u->dtheta)) {
        loc->counters.bad_motions++;
        return RSM_ERR_RANGE;
    }
    /* Odometry's systematic errors, as matching has found them. */
    v = calibrating(loc) ? rsm_odometry_cal_apply(&loc->odo_cal, u) : *u;
    rsm_odometry_noise(&loc->odo.cfg, &v, q);
    before = loc->ekf;
    /* No process noise before the first scan (see localizer.h). */
    if (rsm_ekf_predict(&loc->ekf, &v, loc->have_scan ? q : NULL) != RSM_OK) {
        loc->counters.bad_motions++;
        return RSM_ERR_RANGE;
    }
    if (calibrating(loc)) {
        rsm_odometry_cal_count(&loc->odo_cal, &loc->cfg->odometry_cal, u, loc->have_scan ? q[0] : 0.0f);
    }
    if (loc->cfg->method == RSM_METHOD_MAP) {
        const rsm_pose_t step = {v.dx, v.dy, v.dtheta};
        walk(loc, &v, &before);
        loc->state.persistent.since = rsm_pose_compose(&loc->state.persistent.since, &step);
    }
    loc->counters.motions++;
    return RSM_OK;
}

int rsm_localizer_ticks(rsm_localizer_t *loc, uint32_t left, uint32_t right)
{
    rsm_motion_t u;
    int rc;
    if (!ready(loc)) {
        return RSM_ERR_INVAL;
    }
    rc = rsm_odometry_update_ticks(&loc->odo, left, right, &u);
    if (rc != RSM_OK) {
        return rc;
    }
    return rsm_localizer_motion(loc, &u);
}

int rsm_localizer_set_odometry(rsm_localizer_t *loc, const rsm_odometry_config_t *odo_cfg)
{
    int rc;
    if (!ready(loc)) {
        return RSM_ERR_INVAL;
    }
    rc = rsm_odometry_set_config(&loc->odo, odo_cfg);
    if (rc == RSM_OK) {
        /* A new geometry: what was learnt under the old one is void. */
        rsm_odometry_cal_init(&loc->odo_cal);
    }
    return rc;
}

size_t rsm_localizer_scan_points(const rsm_localizer_t *loc, rsm_point_t *out, size_t cap)
{
    size_t n;
    size_t k;
    if (!ready(loc)) {
        return 0u;
    }
    n = loc->last.points <= RSM_MAX_BEAMS ? (size_t)loc->last.points : (size_t)RSM_MAX_BEAMS;
    for (k = 0; out != NULL && k < n && k < cap; ++k) {
        out[k] = loc->pts[k];
    }
    return n;
}

int rsm_localizer_map_occupancy(const rsm_localizer_t *loc, float x, float y, float *occupancy)
{
    if (!ready(loc) || occupancy == NULL) {
        return RSM_ERR_INVAL;
    }
    if (loc->cfg->method != RSM_METHOD_MAP) {
        return RSM_ERR_NOSYS;
    }
    *occupancy = rsm_tmap_occupancy(&loc->state.persistent.map, 0u, x, y);
    return RSM_OK;
}

int rsm_localizer_map_bounds(const rsm_localizer_t *loc, float *x0, float *y0, float *x1, float *y1)
{
    int32_t g[4];
    float a;
    if (!ready(loc) || x0 == NULL || y0 == NULL || x1 == NULL || y1 == NULL) {
        return RSM_ERR_INVAL;
    }
    if (loc->cfg->method != RSM_METHOD_MAP) {
        return RSM_ERR_NOSYS;
    }
    if (!rsm_tmap_bounds(&loc->state.persistent.map, 0u, &g[0], &g[1], &g[2], &g[3])) {
        return RSM_ERR_DEGENERATE;
    }
    a = rsm_tmap_cell(&loc->state.persistent.map, 0u);
    *x0 = (float)g[0] * a;
    *y0 = (float)g[1] * a;
    *x1 = (float)(g[2] + 1) * a;
    *y1 = (float)(g[3] + 1) * a;
    return RSM_OK;
}

rsm_pose_t rsm_localizer_pose(const rsm_localizer_t *loc)
{
    if (!ready(loc)) {
        const rsm_pose_t none = {NAN, NAN, NAN};
        return none;
    }
    return loc->ekf.x;
}

/* The filter's covariance as reported: with the floors of what matching
 * cannot see on the diagonal. */
static void reported_cov(const rsm_localizer_t *loc, float out[9])
{
    memcpy(out, loc->ekf.p, 9u * sizeof out[0]);
    out[0] += loc->cfg->cov_floor_m * loc->cfg->cov_floor_m;
    out[4] += loc->cfg->cov_floor_m * loc->cfg->cov_floor_m;
    out[8] += loc->cfg->cov_floor_rad * loc->cfg->cov_floor_rad;
}

int rsm_localizer_covariance(const rsm_localizer_t *loc, float out[9])
{
    if (!ready(loc) || out == NULL) {
        return RSM_ERR_INVAL;
    }
    reported_cov(loc, out);
    return RSM_OK;
}

static void to_world(rsm_localizer_t *loc, const rsm_pose_t *pose, size_t n)
{
    float c;
    float s;
    size_t k;
    rsm_sincosf(pose->theta, &s, &c);
    for (k = 0; k < n; ++k) {
        loc->frame.world[k].x = pose->x + c * loc->pts[k].x - s * loc->pts[k].y;
        loc->frame.world[k].y = pose->y + s * loc->pts[k].x + c * loc->pts[k].y;
    }
}

/* Patch reader over the thresholded map. */
typedef struct map_src {
    const rsm_map_t *map;
    uint8_t min_hits;
} map_src_t;

static uint32_t patch_map(const void *ctx, int32_t gx, int32_t gy)
{
    const map_src_t *src = (const map_src_t *)ctx;
    const rsm_window_t *w = &src->map->win;
    uint32_t patch = 0;
    uint32_t bit = 0;
    int32_t dy;
    int32_t dx;
    if (rsm_window_contains(w, gx - 2, gy - 2) && rsm_window_contains(w, gx + 2, gy + 2)) {
        /* Whole patch inside the window: index storage directly. */
        const uint32_t m = (uint32_t)RSM_MAP_SIZE - 1u;
        for (dy = -2; dy <= 2; ++dy) {
            const uint32_t row = ((uint32_t)(gy + dy) & m) << RSM_MAP_SIZE_LOG2;
            for (dx = -2; dx <= 2; ++dx) {
                if (src->map->hits[row | ((uint32_t)(gx + dx) & m)] >= src->min_hits) {
                    patch |= 1u << bit;
                }
                ++bit;
            }
        }
        return patch;
    }
    for (dy = -2; dy <= 2; ++dy) {
        for (dx = -2; dx <= 2; ++dx) {
            if (rsm_map_hits(src->map, gx + dx, gy + dy) >= src->min_hits) {
                patch |= 1u << bit;
            }
            ++bit;
        }
    }
    return patch;
}

/* Key points of the current image. */
static size_t current_keypoints(rsm_localizer_t *loc)
{
    const rsm_window_t *w = &loc->state.paper.map.win;
    rsm_harris_image_src_t src;
    size_t n = loc->state.paper.image.count < RSM_MAX_CANDIDATES ? loc->state.paper.image.count : RSM_MAX_CANDIDATES;
    size_t k;
    int got;
    for (k = 0; k < n; ++k) {
        loc->state.paper.cands[k] = rsm_window_cell(w, loc->state.paper.image.cells[k]);
    }
    src.img = &loc->state.paper.image;
    src.win = w;
    got = rsm_harris_detect(&loc->cfg->harris, &loc->state.paper.harris, rsm_harris_patch_image, &src, loc->state.paper.cands, n,
                            loc->state.paper.kp_cur, RSM_MAX_KEYPOINTS, NULL);
    return got > 0 ? (size_t)got : 0u;
}

/* Key points of the reference map near the current scan's cells: only map
 * cells within radius cells of an occupied current cell are candidates. */
static size_t reference_keypoints(rsm_localizer_t *loc, int32_t radius)
{
    const rsm_window_t *w = &loc->state.paper.map.win;
    const uint8_t min_hits = loc->cfg->map_min_hits;
    uint32_t *visited = loc->state.paper.visited;
    map_src_t src;
    size_t n = 0;
    size_t k;
    int got;
    for (k = 0; k < loc->state.paper.image.count && n < RSM_MAX_CANDIDATES; ++k) {
        const rsm_cell_t c = rsm_window_cell(w, loc->state.paper.image.cells[k]);
        int32_t dy;
        int32_t dx;
        for (dy = -radius; dy <= radius && n < RSM_MAX_CANDIDATES; ++dy) {
            for (dx = -radius; dx <= radius && n < RSM_MAX_CANDIDATES; ++dx) {
                if (rsm_map_hits(&loc->state.paper.map, c.gx + dx, c.gy + dy) >= min_hits) {
                    const uint32_t i = rsm_window_index(c.gx + dx, c.gy + dy);
                    const uint32_t bit = 1u << (i & 31u);
                    if ((visited[i >> 5] & bit) == 0u) {
                        visited[i >> 5] |= bit;
                        loc->state.paper.cands[n].gx = c.gx + dx;
                        loc->state.paper.cands[n].gy = c.gy + dy;
                        ++n;
                    }
                }
            }
        }
    }
    /* Candidates are the only bits set: clearing them empties the set. */
    for (k = 0; k < n; ++k) {
        const uint32_t i = rsm_window_index(loc->state.paper.cands[k].gx, loc->state.paper.cands[k].gy);
        visited[i >> 5] &= ~(1u << (i & 31u));
    }
    src.map = &loc->state.paper.map;
    src.min_hits = min_hits;
    got = rsm_harris_detect(&loc->cfg->harris, &loc->state.paper.harris, patch_map, &src, loc->state.paper.cands, n, loc->state.paper.kp_ref,
                            RSM_MAX_KEYPOINTS, NULL);
    return got > 0 ? (size_t)got : 0u;
}

/* Key point centres in metres relative to the predicted robot position. */
static void keypoints_to_points(const rsm_keypoint_t *kp, size_t n, float a, const rsm_pose_t *origin,
                                rsm_point_t *out)
{
    size_t k;
    for (k = 0; k < n; ++k) {
        out[k].x = ((float)kp[k].gx + 0.5f) * a - origin->x;
        out[k].y = ((float)kp[k].gy + 0.5f) * a - origin->y;
    }
}

/* Measurement noise from the fit: residual spread over the inliers, with
 * the angle's lever arm from how far the inliers spread around the robot. */
static void measurement_noise(const rsm_localizer_config_t *cfg, float rms, uint32_t inliers, float spread2,
                              float r[9])
{
    float sxy2;
    float sth2;
    memset(r, 0, 9 * sizeof r[0]);
    if (cfg->noise == RSM_NOISE_FIXED) {
        const float cell = cfg->grid.cell_m;
        const float th = 0.25f * RSM_PI / 180.0f;
        r[0] = cell * cell;
        r[4] = cell * cell;
        r[8] = th * th;
        return;
    }
    {
        const float quant = cfg->grid.cell_m * 0.2887f; /* a / sqrt(12): one cell's rounding */
        const float e2 = rms * rms + quant * quant;
        const float n = inliers > 2u ? (float)inliers - 2.0f : 1.0f;
        sxy2 = e2 / n + cfg->r_min_xy_m * cfg->r_min_xy_m;
        sth2 = e2 / (n * (spread2 > 0.01f ? spread2 : 0.01f)) + cfg->r_min_theta_rad * cfg->r_min_theta_rad;
    }
    r[0] = sxy2;
    r[4] = sxy2;
    r[8] = sth2;
}

/* R from the map fit: cost-scaled inverse information, floored. Falls back
 * to the RANSAC-based r (unchanged) if the information is singular. */
static void refined_noise(const rsm_localizer_config_t *cfg, const rsm_map_fit_t *fit, float r[9])
{
    float inv[9];
    float s2;
    size_t k;
    if (cfg->noise == RSM_NOISE_FIXED || fit->used < 4u || rsm_mat3_inverse(fit->info, inv) != RSM_OK) {
        return;
    }
    s2 = cfg->refine_noise_scale * fit->cost * (float)fit->used / (float)(fit->used - 3u);
    for (k = 0; k < 9; ++k) {
        r[k] = s2 * inv[k];
    }
    r[0] += cfg->r_min_xy_m * cfg->r_min_xy_m;
    r[4] += cfg->r_min_xy_m * cfg->r_min_xy_m;
    r[8] += cfg->r_min_theta_rad * cfg->r_min_theta_rad;
}

static float search_radius(const rsm_localizer_t *loc)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    const float *p = loc->ekf.p;
    /* Position std plus the heading std acting over a typical 3 m lever. */
    const float sd = sqrtf((p[0] > p[4] ? p[0] : p[4])) + 3.0f * sqrtf(p[8]);
    float r = cfg->search_sigmas * sd;
    if (!(r >= cfg->search_min_m)) {
        r = cfg->search_min_m;
    }
    if (r > cfg->search_max_m) {
        r = cfg->search_max_m;
    }
    return r;
}

/* Fuses measurement z; returns the outcome. */
static rsm_outcome_t fuse(rsm_localizer_t *loc, const rsm_pose_t *z, const float r[9], rsm_localizer_report_t *rep)
{
    float d2 = 0.0f;
    int rc;
    rep->measured = *z;
    if (rsm_ekf_mahalanobis(&loc->ekf, z, r, &d2) != RSM_OK) {
        return RSM_SCAN_FILTER;
    }
    rep->mahalanobis_d2 = d2;
    rc = rsm_ekf_update(&loc->ekf, z, r, loc->cfg->gate_d2);
    if (rc == RSM_ERR_RANGE) {
        return RSM_SCAN_JUMP;
    }
    return rc == RSM_OK ? RSM_SCAN_ACCEPTED : RSM_SCAN_FILTER;
}

static rsm_outcome_t step_rsm(rsm_localizer_t *loc, size_t npts, rsm_localizer_report_t *rep, stage_clock_t *clk)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    const float a = cfg->grid.cell_m;
    const rsm_pose_t pred = loc->ekf.x;
    rsm_ransac_result_t rr;
    size_t nkc;
    size_t nkr;
    int nm;
    float radius_m;
    float r[9];
    int32_t radius_cells;

    stage_switch(clk, RSM_STAGE_GRID);
    (void)rsm_map_recenter(&loc->state.paper.map, pred.x, pred.y);
    to_world(loc, &pred, npts);
    rsm_image_clear(&loc->state.paper.image);
    (void)rsm_image_mark_points(&loc->state.paper.image, &loc->state.paper.map.win, &cfg->grid, loc->frame.world, npts);
    if (!loc->have_scan) {
        return RSM_SCAN_FIRST;
    }
    stage_switch(clk, RSM_STAGE_HARRIS);
    nkc = current_keypoints(loc);
    rep->keypoints_cur = (uint32_t)nkc;
    if (nkc < cfg->min_keypoints) {
        return RSM_SCAN_FEW_KEYPOINTS;
    }
    radius_m = search_radius(loc);
    radius_cells = (int32_t)rsm_ceilf(radius_m / a) + 1;
    nkr = reference_keypoints(loc, radius_cells);
    rep->keypoints_ref = (uint32_t)nkr;
    if (nkr < cfg->min_keypoints) {
        return RSM_SCAN_FEW_KEYPOINTS;
    }
    stage_switch(clk, RSM_STAGE_MATCH);
    keypoints_to_points(loc->state.paper.kp_cur, nkc, a, &pred, loc->state.paper.pt_cur);
    keypoints_to_points(loc->state.paper.kp_ref, nkr, a, &pred, loc->state.paper.pt_ref);
    nm = rsm_match_tentative(loc->state.paper.pt_ref, nkr, loc->state.paper.pt_cur, nkc, radius_m, cfg->match_window_m, loc->state.paper.matches,
                             RSM_MAX_MATCHES, NULL);
    rep->matches = nm > 0 ? (uint32_t)nm : 0u;
    if (nm < 2 || (uint32_t)nm < cfg->ransac.min_support) {
        return RSM_SCAN_FEW_MATCHES;
    }
    stage_switch(clk, RSM_STAGE_RANSAC);
    if (rsm_ransac_estimate(&loc->state.paper.ransac, loc->state.paper.pt_ref, loc->state.paper.pt_cur, loc->state.paper.matches, (size_t)nm, &rr) != RSM_OK) {
        rep->inliers = rr.support;
        rep->iterations = rr.iterations;
        return RSM_SCAN_LOW_SUPPORT;
    }
    rep->inliers = rr.support;
    rep->iterations = rr.iterations;
    rep->residual_m = rr.rms_m;
    {
        /* The robot sits at the origin of the matching frame, so the
         * corrected pose is T applied to it. */
        float spread2 = 0.0f;
        size_t k;
        uint32_t cnt = 0;
        rsm_pose_t z;
        for (k = 0; k < (size_t)nm; ++k) {
            if (loc->state.paper.ransac.inlier[k]) {
                const rsm_point_t *p = &loc->state.paper.pt_cur[loc->state.paper.matches[k].cur];
                spread2 += p->x * p->x + p->y * p->y;
                ++cnt;
            }
        }
        spread2 = cnt > 0 ? spread2 / (float)cnt : 0.0f;
        z.x = pred.x + rr.t.x;
        z.y = pred.y + rr.t.y;
        z.theta = rsm_wrap_angle(pred.theta + rr.t.theta);
        measurement_noise(cfg, rr.rms_m, rr.support, spread2, r);
        stage_switch(clk, RSM_STAGE_REFINE);
        if (cfg->refine_iterations > 0u) {
            rsm_map_fit_t fit;
            if (rsm_map_align(&loc->state.paper.map, loc->pts, npts, &z, cfg->refine_saturation, cfg->refine_iterations, &fit) ==
                    RSM_OK &&
                fit.iterations > 0u) {
                z = fit.pose;
                refined_noise(cfg, &fit, r);
            }
        }
        stage_switch(clk, RSM_STAGE_EKF);
        return fuse(loc, &z, r, rep);
    }
}

/* Drops the returns behind a surface their neighbours span (in the laser's
 * frame, before the mount moves them); returns how many are left. */
static size_t drop_occluded(rsm_localizer_t *loc, size_t n)
{
    uint8_t hidden[(RSM_MAX_BEAMS + 7) / 8];
    size_t kept = 0;
    size_t k;
    if (rsm_points_occluded(loc->pts, n, &loc->cfg->occlusion, hidden) == 0u) {
        return n;
    }
    for (k = 0; k < n; ++k) {
        if (rsm_bit_get(hidden, k)) {
            loc->counters.occluded++;
        } else {
            loc->pts[kept++] = loc->pts[k];
        }
    }
    return kept;
}

/* One more equation for the odometry calibration from a scan matched on its
 * own: the heading's weight is the share of the heading's variance the
 * match removed (a scan that pins the heading tells the most); the
 * position's covariance tells whether it pinned the distance. A
 * recovery's jump, or a step of odometry's the scan refuted, is odometry
 * off by more than its systematic error: a new reference only. */
static void calibrate(rsm_localizer_t *loc, rsm_outcome_t outcome, float prior_var, int jumped)
{
    const rsm_pose_t est = loc->ekf.x;
    if (outcome == RSM_SCAN_FIRST || (outcome == RSM_SCAN_ACCEPTED && jumped)) {
        rsm_odometry_cal_reference(&loc->odo_cal, &est);
    } else if (outcome == RSM_SCAN_ACCEPTED) {
        const float pos_cov[3] = {loc->ekf.p[0], loc->ekf.p[1], loc->ekf.p[4]};
        const float w = prior_var > 0.0f ? 1.0f - loc->ekf.p[8] / prior_var : 0.0f;
        rsm_odometry_cal_update(&loc->odo_cal, &loc->cfg->odometry_cal, &est, w > 1.0f ? 1.0f : w, pos_cov);
    }
}

/* Robot-frame points from laser-frame ones: the mounting pose (and a
 * mirror for an upside-down laser). */
static void apply_mount(rsm_localizer_t *loc, size_t n)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    const rsm_pose_t *m = &cfg->laser_mount;
    size_t k;
    if (m->x == 0.0f && m->y == 0.0f && m->theta == 0.0f && !cfg->laser_upside_down) {
        return;
    }
    {
        float c;
        float s;
        rsm_sincosf(m->theta, &s, &c);
        for (k = 0; k < n; ++k) {
            const float lx = loc->pts[k].x;
            const float ly = cfg->laser_upside_down ? -loc->pts[k].y : loc->pts[k].y;
            loc->pts[k].x = m->x + c * lx - s * ly;
            loc->pts[k].y = m->y + s * lx + c * ly;
        }
    }
}

/* The conflict check (conflict_max): beams are looked at on the finest
 * level, up to CONFLICT_BEAMS of them spread over the scan (a share needs
 * no more, and each costs a walk of its length), and a wall counts only
 * more than CONFLICT_MARGIN cells before the return, so that a return a
 * little off its wall (noise, a match a cell off) or a beam grazing a wall
 * near its end does not count. */
#define CONFLICT_BEAMS 64u
#define CONFLICT_MARGIN 4u

/* Whether the scan placed at pose contradicts the map: more than
 * conflict_max of its beams pass through walls of the persistent map;
 * *share gets the share (when the check is on). */
static int contradicts(rsm_localizer_t *loc, const rsm_pose_t *pose, size_t npts, float *share)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    const rsm_point_t origin = {cfg->laser_mount.x, cfg->laser_mount.y};
    uint32_t checked = 0;
    uint32_t crossing;
    if (cfg->conflict_max <= 0.0f) {
        return 0;
    }
    crossing = rsm_tmap_beams_crossing(&loc->state.persistent.map, 0u, pose, &origin, loc->pts, npts,
                                       (npts + CONFLICT_BEAMS - 1u) / CONFLICT_BEAMS, cfg->tmap.saturation,
                                       CONFLICT_MARGIN, &checked);
    *share = checked > 0u ? (float)crossing / (float)checked : 0.0f;
    return *share > cfg->conflict_max;
}


/* Whether odometry reported any motion since the last scan's estimate: a
 * stalled odometry repeats its pose exactly, and so predicts exactly that
 * estimate (compared as is: the step between them, computed, is not 0 but
 * rounding far from the origin). */
static int moved(const rsm_pose_t *anchor, const rsm_pose_t *pred)
{
    return anchor->x != pred->x || anchor->y != pred->y || anchor->theta != pred->theta;
}

/* Whether odometry's steps are checked against the scans. */
static int refuting(const rsm_localizer_config_t *cfg)
{
    return cfg->method == RSM_METHOD_MAP && cfg->refute_margin > 0.0f;
}

/* Whether b is at least doubt_m or doubt_rad from a. */
static int beyond_doubt(const rsm_localizer_config_t *cfg, const rsm_pose_t *a, const rsm_pose_t *b)
{
    return rsm_pose_apart(a, b, cfg->doubt_m, cfg->doubt_rad);
}

/* Whether odometry since the last scan left its prediction too uncertain
 * for a match from it alone (a long gap in the scans): it added more than
 * (twice doubt_m)^2 to the position's variance, or more than recover_rad^2
 * to the heading's. A plain match then lands in whichever basin lies
 * nearest, and one that fits fairly (a corridor a metre along) is not poor
 * enough to search by its fit; the search around the prediction compares
 * the basins. What odometry added, not the variance itself: along a
 * corridor the matches leave the position to odometry (unpinned) and its
 * variance stays large for many scans, and a search on each of them is a
 * chance on each for a look-alike to win. Never on the clean Intel and
 * ACES logs (the variances themselves stay below 0.08 m and 0.13 rad
 * there); after 15 s without a scan, from odometry reported in one step
 * (step_map takes the walk's prior, rsm_odometry_noise_walk), only when
 * the robot drove more than about 6 m (the heading's share) or turned
 * a lot meanwhile. Only after a
 * gap of UNSURE_GAP_S: a large step in a scan's time is a stall's
 * catch-up, a spike or a reset, which doubt_step weighs (searched as well,
 * a stall's catch-up took 8 poses off by the ground truth in 20 ACES
 * runs). */
#define UNSURE_GAP_S 1.0f
static int unsure(const rsm_localizer_t *loc, float dt_s)
{
    const float *p = loc->ekf.p;
    const float *q = loc->last.cov;
    const float m = 2.0f * loc->cfg->doubt_m;
    return dt_s > UNSURE_GAP_S &&
           ((p[0] + p[4]) - (q[0] + q[4]) > m * m || p[8] - q[8] > loc->cfg->recover_rad * loc->cfg->recover_rad);
}

/* Whether odometry's step to pred could be the robot's own over dt_s
 * seconds: no farther than the fastest plausible wheel goes. */
static int plausible_step(const rsm_localizer_t *loc, const rsm_pose_t *pred, float dt_s)
{
    const rsm_pose_t d = rsm_pose_between(&loc->state.persistent.anchor, pred);
    return sqrtf(d.x * d.x + d.y * d.y) <= loc->cfg->odometry.max_wheel_speed_mps * dt_s;
}

/* Odometry's step from the last scan's estimate to pred, checked against the
 * scan (res: the match from pred, rc its status). Two other predictions are
 * matched when there is cause:
 * - odometry counted from the last scan that trusted it, when that differs
 *   from the step by doubt_m or doubt_rad: after a stall (odometry stood
 *   still while matching found the robot move) the step reports that motion
 *   again, and after a refuted spike the step takes the spike back;
 * - the last estimate without the step, when the match from pred fits
 *   poorly or moved pred by more than a doubt: the step may be false (a
 *   spike, a counter reset, wheels that slipped). Not after a gap in the
 *   scans when the step is one the robot could have driven in the time
 *   (driven): odometry is then the only evidence of
 *   where it went, the ground there may not be mapped yet, and the place
 *   it left fits as well as any stretch of corridor alike (ACES, 10 m in
 *   15 s, "refuted" into a 10 m error); the search around pred decides.
 * One replaces the match from pred only when it fits as well as recent
 * scans (recover_ratio of their fit: with many outliers in the scans a
 * poor fit beating a poorer one drops true steps) and beats pred's fit by
 * refute_margin (or pred found no match at all), except where odometry
 * counted from the last trusted scan is the better-founded prediction:
 * then pred's match must beat it so. The scan, not the order of the tries,
 * decides. After a stall in which matching found the robot
 * move, either one winning says the step repeated that motion (odometry
 * and matching need not agree on how far the robot went meanwhile, so the
 * last estimate may fit better than odometry counted from the stall's
 * start). The last estimate drops the step only when the scan fits it
 * nearly as well as recent scans (track_min_fit): a step over a long gap
 * in the scans, into ground the map does not hold yet, is poorly matched
 * either way, and a robot that stood still through it is the less likely
 * story; such a weaker case sets *doubted instead, and the caller searches
 * around pred. Returns what was made of the step. */
static rsm_odometry_verdict_t doubt_step(rsm_localizer_t *loc, size_t npts, const rsm_pose_t *pred,
                                         int odometry_moved, int driven, int *rc, rsm_mapmatch_result_t *res,
                                         int *doubted, uint32_t *passes)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    const rsm_pose_t *anchor = &loc->state.persistent.anchor;
    const rsm_pose_t counted = rsm_pose_compose(&loc->state.persistent.trusted, &loc->state.persistent.since);
    rsm_pose_t alt_pred[2];
    rsm_odometry_verdict_t kind[2];
    rsm_odometry_verdict_t verdict = RSM_ODOMETRY_TRUSTED;
    int counted_first = 0;
    int stall_lead = 0; /* a stall in which matching found the robot move */
    size_t n = 0;
    size_t k;
    if (!refuting(cfg) || !odometry_moved) {
        return verdict;
    }
    if (beyond_doubt(cfg, pred, &counted)) {
        const rsm_odometry_verdict_t held = loc->state.persistent.held;
        alt_pred[n] = counted;
        kind[n++] = held;
        /* Past a refuted step, or after a stall in which matching found the
         * robot move, odometry counted from the last trusted scan is the
         * better-founded prediction (the step alone counts the stall's
         * motion twice): there the step's prediction is the one that must
         * fit better, which matters where the building looks alike turned
         * (a corridor crossing). */
        stall_lead = held == RSM_ODOMETRY_CAUGHT_UP && beyond_doubt(cfg, &loc->state.persistent.trusted, anchor);
        counted_first = held == RSM_ODOMETRY_REFUTED || stall_lead;
    }
    if ((*rc != RSM_OK || res->hit < cfg->recover_ratio * loc->state.persistent.fit ||
         beyond_doubt(cfg, pred, &res->pose)) &&
        !driven) {
        /* After a stall in which matching found the robot move, the step
         * repeated that motion; else it was false. */
        alt_pred[n] = *anchor;
        kind[n] = stall_lead ? RSM_ODOMETRY_CAUGHT_UP : RSM_ODOMETRY_REFUTED;
        ++n;
    }
    for (k = 0; k < n; ++k) {
        rsm_mapmatch_unpin_t unpin;
        rsm_mapmatch_result_t alt;
        rsm_mapmatch_unpin_for(&cfg->mapmatch, loc->pts, npts, alt_pred[k].theta, &unpin);
        int ok;
        alt.passes = 0u;
        ok = rsm_mapmatch(&loc->state.persistent.map, &cfg->mapmatch, loc->pts, npts, &alt_pred[k], loc->ekf.p, NULL,
                          &unpin, &alt) == RSM_OK;
        *passes += alt.passes;
        if (ok && alt.used >= cfg->min_points / 2u && alt.hit >= cfg->recover_ratio * loc->state.persistent.fit &&
            (*rc != RSM_OK || (k == 0 && counted_first ? res->hit <= alt.hit * (1.0f + cfg->refute_margin)
                                                       : alt.hit > res->hit * (1.0f + cfg->refute_margin)))) {
            if (kind[k] == RSM_ODOMETRY_REFUTED && *rc == RSM_OK &&
                alt.hit < cfg->track_min_fit * loc->state.persistent.fit) {
                *doubted = 1;
                continue;
            }
            *res = alt;
            *rc = RSM_OK;
            verdict = kind[k];
        }
    }
    return verdict;
}

/* What a recovery made of the scans so far. */
typedef enum recovery {
    RECOVERY_NONE = 0,      /* nothing fitted well enough */
    RECOVERY_TAKEN = 1,     /* *res replaced by a proven winner */
    RECOVERY_AMBIGUOUS = 2, /* a winner, but a pose a doubt away fitted nearly as well */
    RECOVERY_RUNNING = 3    /* more to do in the next scan */
} recovery_t;


/* A new view: the robot moved this far or turned this much (a proof left
 * in doubt, or a recovery that proved nothing, tries again only from one). */
#define PROVE_AGAIN_M 0.3f
#define PROVE_AGAIN_RAD 0.2f

/* Readings a recovery keeps of the scan it searches: as many as its coarse
 * search scores, within the global search's memory for them. */
#define RECOVER_POINTS                                                                                                 \
    (RSM_MAPMATCH_SEARCH_POINTS < 2u * RSM_GLOBAL_POINTS ? RSM_MAPMATCH_SEARCH_POINTS : 2u * RSM_GLOBAL_POINTS)

/* Of them, the coarse search scores every other: it only ranks basins for
 * the descents (which read them all) and the proof (the whole scan). */
#ifndef RECOVER_SEARCH_POINTS
#define RECOVER_SEARCH_POINTS (RECOVER_POINTS / 2u)
#endif

/* What its steps cost, in recover_budget's units (about 18 M4
 * instructions), measured on the M4 (docs/robustness.md, "A recovery
 * spread over scans"): a match's pass over a reading (each reads the
 * reading's cells on one level: rsm_mapmatch_result_t.passes), about 200
 * instructions, and a fit at a pose is one; a match not yet made is
 * counted at RECOVER_MATCH_PASSES, a descent with the kept readings too;
 * the check of a scan against the map's walls (contradicts: 64 beams
 * walked) about 200 000; a heading of the coarse search, a fixed part
 * beside a quarter of RECOVER_CELL_WORK a scored reading at a position
 * (about 30 instructions). */
#define RECOVER_PASS_WORK 11u
#define RECOVER_MATCH_PASSES 16u
#define RECOVER_CONFLICT_WORK 11000u
/* The first stage in the scan that asks for it: its search (RECOVER_SEARCH_POINTS
 * readings at one position, 16 headings) and its proof (a match of the kept
 * readings and a fit). */
#define RECOVER_FIRST_WORK (16u * (RECOVER_HEADING_WORK + RECOVER_SEARCH_POINTS * RECOVER_CELL_WORK / 4u) + \
                            (RECOVER_MATCH_PASSES + 1u) * RECOVER_PASS_WORK * RECOVER_POINTS)
#define RECOVER_HEADING_WORK 200u
#define RECOVER_CELL_WORK 7u

/* The proof's matches' prior: the filter's, and this much more. */
#define PROOF_SLACK_M 0.03f
#define PROOF_SLACK_RAD 0.01f
/* The basins the proof matches: those whose descents with the kept
 * readings fitted at least this share of the best's. */
#define PROOF_BAND 0.7f

static int recovering(const rsm_localizer_t *loc)
{
    const uint8_t phase = loc->state.persistent.recovery.phase;
    return phase != RECOVER_IDLE && phase != RECOVER_RESTING;
}

/* Begins a recovery of the scan at hand (loc->pts), searched around pred
 * (recovery_step's stages), res the match tracking made of it. */
static void recovery_begin(rsm_localizer_t *loc, size_t npts, const rsm_pose_t *pred,
                           const rsm_mapmatch_result_t *res)
{
    rsm_recovery_t *r = &loc->state.persistent.recovery;
    rsm_global_t *g = &loc->state.persistent.global;
    const size_t stride = npts > RECOVER_POINTS ? (npts + RECOVER_POINTS - 1u) / RECOVER_POINTS : 1u;
    size_t q;
    uint32_t m = 0;
    /* The readings the coarse search would score of the whole scan. */
    for (q = 0; q < npts; q += stride) {
        g->pts[m++] = loc->pts[q];
    }
    g->npts = m;
    r->phase = RECOVER_SEARCHING;
    r->stage = 0u;
    r->fresh = 1u;
    r->found = 0u;
    r->done = 0u;
    r->heading = -RSM_MAPMATCH_MAX_FAN;
    r->radius_m = 0.0f;
    memcpy(r->prior, loc->ekf.p, sizeof r->prior);
    r->pred = *pred;
    r->tracked = res->pose;
    r->base = *pred;
}

/* The verdict on a recovery's basins, fitted with one scan (hit[k] at
 * end[k]; below 0: no fit), beside the tracked pose's fit (tracked_hit at
 * tracked): basin best wins if it fits well again (recover_ratio of recent
 * scans, and half of what the tracked pose lost regained) and beats every
 * pose a doubt away from it (another basin, or the tracked pose) by
 * recover_margin. Both recoveries weigh so: whole in a scan (recover), and
 * spread over scans (recovery_verdict). With share (not NULL: share[k] the
 * wall share at end[k], tracked_share the tracked pose's), best must beat
 * the same rivals by recover_margin in that too: a fit also grows with how
 * often the map saw a wall, and among posts a period apart the place
 * nearer where the robot mapped fitted 16 % better than the true one, both
 * wholly in the map, while their wall shares parted by 8 %. Only the
 * recovery whole in a scan passes shares: the spread one's fits come from
 * kept readings and carried poses, which would need their shares carried
 * through its stages too (not done; recover_budget is off by default). */
static recovery_t recovery_weigh(const rsm_localizer_t *loc, const float *hit, const rsm_pose_t *end, int n, int best,
                                 float tracked_hit, const rsm_pose_t *tracked, const float *share, float tracked_share)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    const float fit = loc->state.persistent.fit;
    const float need = tracked_hit + 0.5f * (fit - tracked_hit);
    float rival;
    float rival_share = 0.0f;
    int k;
    if (best < 0 || !(hit[best] >= cfg->recover_ratio * fit && hit[best] >= need && hit[best] > tracked_hit)) {
        return RECOVERY_NONE;
    }
    rival = 0.0f;
    if (beyond_doubt(cfg, tracked, &end[best])) {
        rival = tracked_hit;
        rival_share = tracked_share;
    }
    for (k = 0; k < n; ++k) {
        if (k != best && hit[k] >= 0.0f && beyond_doubt(cfg, &end[k], &end[best])) {
            rival = hit[k] > rival ? hit[k] : rival;
            if (share != NULL && share[k] > rival_share) {
                rival_share = share[k];
            }
        }
    }
    if (hit[best] <= rival * (1.0f + cfg->recover_margin)) {
        return RECOVERY_AMBIGUOUS;
    }
    /* A rival with no reading on a wall is none to beat in shares. */
    return share != NULL && rival_share > 0.0f && share[best] <= rival_share * (1.0f + cfg->recover_margin)
               ? RECOVERY_AMBIGUOUS
               : RECOVERY_TAKEN;
}

/* The spread recovery's verdict on its basins' fits with the scan of the
 * proof (recovery_weigh); the winner into r->best. */
static recovery_t recovery_verdict(rsm_localizer_t *loc, const rsm_pose_t *tracked)
{
    rsm_recovery_t *r = &loc->state.persistent.recovery;
    recovery_t v;
    int best = -1;
    int k;
    for (k = 0; k < (int)r->found; ++k) {
        if (r->hit[k] >= 0.0f && (best < 0 || r->hit[k] > r->hit[best])) {
            best = k;
        }
    }
    v = recovery_weigh(loc, r->hit, r->end, (int)r->found, best, r->tracked_hit, tracked, NULL, 0.0f);
    if (v == RECOVERY_TAKEN) {
        r->best = (uint8_t)best;
    }
    return v;
}

/* Ends a recovery without a pose: none begins again before a new view. */
static recovery_t recovery_rest(rsm_localizer_t *loc, recovery_t v)
{
    loc->state.persistent.recovery.phase = RECOVER_RESTING;
    loc->state.persistent.recovery.base = loc->ekf.x;
    return v;
}

/* A pose of the scan searched carried by odometry to the scan at hand, and
 * back. */
static rsm_pose_t recovery_carry(const rsm_localizer_t *loc, const rsm_pose_t *then)
{
    const rsm_pose_t moved_by = rsm_pose_between(&loc->state.persistent.recovery.base, &loc->ekf.x);
    return rsm_pose_compose(then, &moved_by);
}

static rsm_pose_t recovery_uncarry(const rsm_localizer_t *loc, const rsm_pose_t *now)
{
    const rsm_pose_t back = rsm_pose_between(&loc->ekf.x, &loc->state.persistent.recovery.base);
    return rsm_pose_compose(now, &back);
}

/* The scan at hand matched from a basin's pose (of the scan searched) carried
 * to it, free to settle a little farther than the filter's prior says (the
 * descent with the kept readings placed it no closer). */
static int recovery_match(rsm_localizer_t *loc, size_t npts, const rsm_pose_t *then, rsm_mapmatch_result_t *m)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    const rsm_pose_t from = recovery_carry(loc, then);
    rsm_mapmatch_unpin_t unpin;
    float prior[9];
    memcpy(prior, loc->ekf.p, sizeof prior);
    prior[0] += PROOF_SLACK_M * PROOF_SLACK_M;
    prior[4] += PROOF_SLACK_M * PROOF_SLACK_M;
    prior[8] += PROOF_SLACK_RAD * PROOF_SLACK_RAD;
    rsm_mapmatch_unpin_for(&cfg->mapmatch, loc->pts, npts, from.theta, &unpin);
    return rsm_mapmatch(&loc->state.persistent.map, &cfg->mapmatch, loc->pts, npts, &from, prior, NULL, &unpin, m) ==
               RSM_OK &&
           m->used >= cfg->min_points / 2u;
}

/* Whether the winner's match m may be taken: one that would not track by
 * its fit (track_min_fit) and contradicts the map (conflict_max: a look-alike
 * place within reach of a robot carried farther) may not. */
static int recovery_takes(rsm_localizer_t *loc, size_t npts, const rsm_mapmatch_result_t *m)
{
    float share;
    return m->hit >= loc->cfg->recover_ratio * loc->state.persistent.fit &&
           !(m->hit < loc->cfg->track_min_fit * loc->state.persistent.fit && contradicts(loc, &m->pose, npts, &share));
}

/* Whether a first-stage winner's match (at) kept to where the search of
 * headings only placed it (from), within half a coarse cell: one that slid
 * farther is no misjudged turn, and had no rival weighed there. */
static int recovery_kept_place(const rsm_localizer_t *loc, const rsm_pose_t *from, const rsm_pose_t *at)
{
    const rsm_tmap_t *map = &loc->state.persistent.map;
    return !rsm_pose_apart(from, at, 0.5f * rsm_tmap_cell(map, (uint32_t)loc->cfg->tmap.levels - 1u), RSM_PI);
}

/* Runs the recovery in progress for one scan, within recover_budget (above
 * 0; spent: the work this scan did before, in its units). must: a scan
 * after the one that asked, whose first step is taken whatever it costs, so
 * that every scan given to a recovery moves it on; else the scan that
 * asked, where only the first stage runs:
 * - the coarse search, a few headings at a time;
 * - a descent a basin with the readings kept of the scan searched: where
 *   each basin is;
 * - the proof: the basins that fitted within PROOF_BAND of the best, one a
 *   scan, each carried by odometry to the scan at hand and matched with it,
 *   the best last; then, with the last scan, every one's fit at its match
 *   carried there and the tracked pose's, and the verdict on them (a few
 *   dozen kept readings tell look-alike basins apart less surely than a
 *   whole scan: a row of posts a period apart fitted 0.28 and 0.23 with
 *   them, 0.31 and 0.23 so matched);
 * - the winner, when not the basin matched last, matched with the next scan.
 * A search within a coarse cell that proves nothing is followed by one
 * within recover_m (an ambiguous one is not: a farther pose would have the
 * same rival, and the wider search might not see it). RECOVERY_TAKEN leaves
 * the winner's match with the scan at hand in *res. */
static recovery_t recovery_step(rsm_localizer_t *loc, size_t npts, uint32_t spent, int must,
                                 rsm_mapmatch_result_t *res)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    const rsm_tmap_t *map = &loc->state.persistent.map;
    rsm_recovery_t *r = &loc->state.persistent.recovery;
    rsm_global_t *g = &loc->state.persistent.global;
    const uint32_t budget = cfg->recover_budget;
    const uint32_t started = must ? spent : 0u;
    /* The scan that asks for a recovery: its first stage is cheap (one
     * position, a few dozen readings) and runs there whatever the budget,
     * so that a turn misjudged is put right in that scan. */
    const int first = !must;
    const uint32_t match_work = RECOVER_MATCH_PASSES * RECOVER_PASS_WORK * (uint32_t)npts;
    const uint32_t fit_work = RECOVER_PASS_WORK * (uint32_t)npts;
    uint32_t work = spent;
    if (must && r->fresh) {
        /* The scan searched went its way (kept at its prediction);
         * odometry carries the basins on from where it ended. */
        r->fresh = 0u;
        r->base = loc->state.persistent.anchor;
    }
    for (;;) {
        if (r->phase == RECOVER_SEARCHING) {
            const uint32_t scored = g->npts > RECOVER_SEARCH_POINTS ? RECOVER_SEARCH_POINTS : g->npts;
            int32_t fan;
            uint32_t positions;
            uint32_t each;
            uint32_t count;
            size_t found = r->found;
            /* Headings only (stage 0): twice as far apart, the match of
             * the proof sets the heading within them. */
            rsm_mapmatch_config_t mm = cfg->mapmatch;
            mm.search_step_rad *= r->stage == 0u ? 2.0f : 1.0f;
            if (rsm_mapmatch_search_size(map, &mm, r->radius_m, cfg->recover_rad, &fan, &positions) !=
                RSM_OK) {
                return recovery_rest(loc, RECOVERY_NONE);
            }
            r->heading = r->heading < -fan ? -fan : r->heading;
            each = RECOVER_HEADING_WORK + (positions * scored * RECOVER_CELL_WORK) / 4u;
            count = (uint32_t)(fan + 1 - r->heading);
            if (!(first && r->stage == 0u)) {
                const uint32_t room = work < budget ? (budget - work) / each : 0u;
                if (room == 0u && work > started) {
                    return RECOVERY_RUNNING;
                }
                count = room < 1u ? 1u : room < count ? room : count;
            }
            (void)rsm_mapmatch_search_part(map, &mm, g->pts, g->npts, &r->pred, r->radius_m,
                                           cfg->recover_rad, r->heading, r->heading + (int32_t)count, r->start,
                                           r->cost, r->ij, RSM_RECOVER_STARTS, &found, RECOVER_SEARCH_POINTS);
            r->found = (uint8_t)found;
            r->heading += (int32_t)count;
            work += count * each;
            if (r->heading > fan) {
                r->phase = RECOVER_DESCENDING;
                r->done = 0u;
                if (r->stage == 0u) {
                    /* One position: its best heading goes to the proof as
                     * the search placed it (the proof's match is its
                     * descent). */
                    uint32_t k;
                    for (k = 0; k < r->found; ++k) {
                        r->end[k] = r->start[k];
                        r->hit[k] = 1.0f;
                    }
                    r->done = r->found;
                }
            }
        } else if (r->phase == RECOVER_DESCENDING) {
            const uint32_t cost = RECOVER_MATCH_PASSES * RECOVER_PASS_WORK * g->npts;
            const uint32_t k = r->done;
            float wide[9];
            rsm_mapmatch_result_t alt;
            if (k == r->found) {
                /* The proof takes the basins that fitted near the best. */
                float top = 0.0f;
                uint32_t j;
                for (j = 0; j < r->found; ++j) {
                    top = r->hit[j] > top ? r->hit[j] : top;
                }
                for (j = 0; j < r->found; ++j) {
                    if (!(r->hit[j] >= PROOF_BAND * top && top > 0.0f)) {
                        r->hit[j] = -1.0f;
                    }
                }
                r->proved = 0u;
                r->phase = RECOVER_PROVING;
                continue;
            }
            if (work > started && work + cost > budget) {
                return RECOVERY_RUNNING;
            }
            work += cost;
            memcpy(wide, r->prior, sizeof wide);
            wide[0] += r->radius_m * r->radius_m;
            wide[4] += r->radius_m * r->radius_m;
            wide[8] += cfg->recover_rad * cfg->recover_rad;
            /* Not unpinned: each starts where the search put it. */
            r->hit[k] = -1.0f;
            if (rsm_mapmatch(map, &cfg->mapmatch, g->pts, g->npts, &r->pred, wide, &r->start[k], NULL, &alt) ==
                RSM_OK) {
                r->hit[k] = alt.hit;
                r->end[k] = alt.pose;
            }
            r->done++;
        } else if (r->phase == RECOVER_PROVING && first && r->stage == 0u) {
            /* A turn misjudged, proven in the scan that asked, with the
             * readings kept of it (a third of its cost matched with all;
             * measured on ACES, alike in accuracy): the best heading's
             * match against the tracked pose's fit, taken as that scan's
             * match. Scans of a fast turn whose odometry misjudged it (ACES)
             * were otherwise placed poorly until a later scan's proof. */
            rsm_mapmatch_result_t m;
            rsm_mapmatch_unpin_t unpin;
            recovery_t v = RECOVERY_NONE;
            float prior[9];
            work += (RECOVER_MATCH_PASSES + 1u) * RECOVER_PASS_WORK * g->npts;
            /* The filter's prior in position; in heading, the search's
             * step (it placed the heading that near): a narrow prior, a
             * descent from a fine level. */
            memcpy(prior, r->prior, sizeof prior);
            prior[2] = prior[5] = prior[6] = prior[7] = 0.0f;
            prior[8] = 4.0f * cfg->mapmatch.search_step_rad * cfg->mapmatch.search_step_rad;
            r->proved = 1u;
            r->hit[0] = -1.0f;
            if (r->found > 0u) {
                rsm_mapmatch_unpin_for(&cfg->mapmatch, g->pts, g->npts, r->start[0].theta, &unpin);
                if (rsm_mapmatch(map, &cfg->mapmatch, g->pts, g->npts, &r->start[0], prior, NULL, &unpin, &m) ==
                        RSM_OK &&
                    m.used >= cfg->min_points / 2u) {
                    r->hit[0] = m.hit;
                    r->end[0] = m.pose;
                    r->tracked_hit = rsm_mapmatch_fit(map, g->pts, g->npts, &r->tracked);
                    v = recovery_verdict(loc, &r->tracked);
                }
            }
            if (v == RECOVERY_TAKEN && recovery_kept_place(loc, &r->start[0], &m.pose) &&
                m.hit >= cfg->track_min_fit * loc->state.persistent.fit) {
                r->phase = RECOVER_IDLE;
                *res = m;
                return RECOVERY_TAKEN;
            }
            /* Else the whole scan weighs the same basin, the next one. */
            r->proved = 0u;
            r->hit[0] = 1.0f;
            r->end[0] = r->start[0];
            return RECOVERY_RUNNING;
        } else if (r->phase == RECOVER_PROVING) {
            /* The next basin to match: the worst-fitting not yet matched. */
            rsm_mapmatch_result_t m;
            recovery_t v;
            int next = -1;
            int last = 1;
            uint32_t k;
            for (k = 0; k < r->found; ++k) {
                if (r->hit[k] >= 0.0f && !(r->proved & (1u << k))) {
                    if (next >= 0) {
                        last = 0;
                    }
                    if (next < 0 || r->hit[k] < r->hit[next]) {
                        next = (int)k;
                    }
                }
            }
            if (next < 0) {
                return recovery_rest(loc, RECOVERY_NONE);
            }
            if (work > started &&
                work + match_work + (last ? fit_work * r->found + RECOVER_CONFLICT_WORK : 0u) > budget) {
                return RECOVERY_RUNNING;
            }
            work += match_work;
            r->proved = (uint8_t)(r->proved | (1u << (uint32_t)next));
            if (recovery_match(loc, npts, &r->end[next], &m)) {
                r->end[next] = recovery_uncarry(loc, &m.pose);
            } else {
                r->hit[next] = -1.0f;
            }
            if (!last) {
                continue;
            }
            /* The verdict, every fit on this scan. */
            work += fit_work * r->found;
            for (k = 0; k < r->found; ++k) {
                if (r->hit[k] >= 0.0f) {
                    const rsm_pose_t at = recovery_carry(loc, &r->end[k]);
                    r->hit[k] = (int)k == next ? m.hit : rsm_mapmatch_fit(map, loc->pts, npts, &at);
                }
            }
            {
                const rsm_pose_t tracked = recovery_carry(loc, &r->tracked);
                r->tracked_hit = rsm_mapmatch_fit(map, loc->pts, npts, &tracked);
                v = recovery_verdict(loc, &r->tracked);
            }
            if (v == RECOVERY_TAKEN && r->stage == 0u &&
                !recovery_kept_place(loc, &r->start[r->best], &r->end[r->best])) {
                /* Only headings were searched, and no rival beside the
                 * tracked pose weighed: the winner's match must have kept
                 * to its place (within half a coarse cell). One that went
                 * farther is no misjudged turn; the next stage searches
                 * its positions, with their rivals. */
                v = RECOVERY_NONE;
            }
            if (v == RECOVERY_NONE && r->stage < 2u) {
                /* The next stage searches the same kept scan around its
                 * prediction, farther: positions within a coarse cell,
                 * then within recover_m. */
                const float near_m = rsm_tmap_cell(map, (uint32_t)cfg->tmap.levels - 1u);
                r->stage = r->stage == 0u && near_m < cfg->recover_m ? 1u : 2u;
                r->radius_m = r->stage == 1u ? near_m : cfg->recover_m;
                r->phase = RECOVER_SEARCHING;
                r->heading = -RSM_MAPMATCH_MAX_FAN;
                r->found = 0u;
                continue;
            }
            if (v == RECOVERY_AMBIGUOUS) {
                loc->counters.ambiguous++;
            }
            if (v != RECOVERY_TAKEN) {
                return recovery_rest(loc, v);
            }
            if ((int)r->best != next) {
                r->phase = RECOVER_TAKING;
                continue;
            }
            if (!recovery_takes(loc, npts, &m)) {
                return recovery_rest(loc, RECOVERY_NONE);
            }
            r->phase = RECOVER_IDLE;
            *res = m;
            return RECOVERY_TAKEN;
        } else if (r->phase == RECOVER_TAKING) {
            rsm_mapmatch_result_t m;
            if (work > started && work + match_work > budget) {
                return RECOVERY_RUNNING;
            }
            if (!recovery_match(loc, npts, &r->end[r->best], &m) || !recovery_takes(loc, npts, &m)) {
                return recovery_rest(loc, RECOVERY_NONE);
            }
            r->phase = RECOVER_IDLE;
            *res = m;
            return RECOVERY_TAKEN;
        } else {
            return RECOVERY_NONE;
        }
    }
}

/* recover_budget 0: one recovery search, whole in the scan that asks for
 * it, within +-radius_m and +-recover_rad of pred: descends
 * from the best few candidates under a prior widened as far and replaces
 * *res with the best fit if it fits well again (at least half of what was
 * lost regained; need is above the first *res, so each replacement fits
 * better than the last) and is proven: it beats every pose a doubt away
 * from it (another basin's descent, or the plain match) by recover_margin.
 * The winner's whole result is kept: descending it again cost a
 * recovery's scan a fifth of a million M4 instructions. A winner
 * that would not track by its fit (track_min_fit) and contradicts the map
 * (conflict_max: a look-alike place within reach of a robot carried
 * farther) is not taken. */
static recovery_t recover(rsm_localizer_t *loc, size_t npts, const rsm_pose_t *pred, float radius_m,
                          rsm_mapmatch_result_t *res)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    rsm_pose_t start[RSM_RECOVER_STARTS];
    rsm_pose_t found_pose[RSM_RECOVER_STARTS];
    rsm_mapmatch_result_t won;
    recovery_t v;
    float share;
    float found_hit[RSM_RECOVER_STARTS];
    float found_share[RSM_RECOVER_STARTS];
    float wide[9];
    int found;
    int k;
    int best = -1;
    for (k = 0; k < RSM_RECOVER_STARTS; ++k) {
        found_hit[k] = -1.0f; /* no basin, until its descent ends */
    }
    memcpy(wide, loc->ekf.p, sizeof wide);
    wide[0] += radius_m * radius_m;
    wide[4] += radius_m * radius_m;
    wide[8] += cfg->recover_rad * cfg->recover_rad;
    found = rsm_mapmatch_search(&loc->state.persistent.map, &cfg->mapmatch, loc->pts, npts, pred, radius_m,
                                cfg->recover_rad, start, RSM_RECOVER_STARTS, RSM_MAPMATCH_SEARCH_POINTS);
    /* The coarse score only ranks basins: descend from each. */
    for (k = 0; k < found; ++k) {
        rsm_mapmatch_result_t alt;
        /* Not unpinned: each descent starts where the search put it and
         * only the fit decides, measured against the plain match. */
        if (rsm_mapmatch(&loc->state.persistent.map, &cfg->mapmatch, loc->pts, npts, pred, wide, &start[k], NULL,
                         &alt) == RSM_OK) {
            found_hit[k] = alt.hit;
            found_pose[k] = alt.pose;
            if (best < 0 || alt.hit > found_hit[best]) {
                best = k;
                won = alt;
            }
        }
    }
    v = recovery_weigh(loc, found_hit, found_pose, found, best, res->hit, &res->pose, NULL, 0.0f);
    if (v == RECOVERY_TAKEN) {
        /* Taken on its fit: weighed on the wall shares too (read only
         * now, the fit's verdict being the same either way). */
        const rsm_tmap_t *map = &loc->state.persistent.map;
        const uint32_t wall = rsm_tmap_wall_value(map);
        for (k = 0; k < found; ++k) {
            found_share[k] = found_hit[k] >= 0.0f ? rsm_mapmatch_wall_share(map, loc->pts, npts, &found_pose[k], wall)
                                                  : 0.0f;
        }
        v = recovery_weigh(loc, found_hit, found_pose, found, best, res->hit, &res->pose, found_share,
                           rsm_mapmatch_wall_share(map, loc->pts, npts, &res->pose, wall));
    }
    if (v != RECOVERY_TAKEN) {
        return v;
    }
    if (won.hit < cfg->track_min_fit * loc->state.persistent.fit && contradicts(loc, &won.pose, npts, &share)) {
        return RECOVERY_NONE;
    }
    *res = won;
    return RECOVERY_TAKEN;
}

/* Whether a recovery may begin at pred: none runs, and one that ended
 * without a pose did so from another view. */
static int recovery_may_begin(const rsm_localizer_t *loc, const rsm_pose_t *pred)
{
    const rsm_recovery_t *r = &loc->state.persistent.recovery;
    return r->phase == RECOVER_IDLE ||
           (r->phase == RECOVER_RESTING && rsm_pose_apart(&r->base, pred, PROVE_AGAIN_M, PROVE_AGAIN_RAD));
}

/* What step_map makes of its match (rc, res) once any recovery is done:
 * refused, fused, and the recent fit updated. poor: it fitted far worse
 * than recent scans and no search proved a pose; ambiguous: a search
 * found rival poses. */
static rsm_outcome_t settle(rsm_localizer_t *loc, size_t npts, int odometry_moved, int rc,
                            const rsm_mapmatch_result_t *r, int poor, int ambiguous, rsm_localizer_report_t *rep,
                            stage_clock_t *clk, int *contradicted)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    const rsm_mapmatch_result_t res = *r;
    rep->inliers = res.used;
    rep->iterations = res.iterations;
    rep->measured = res.pose;
    rep->mahalanobis_d2 = res.d2;
    if (rc == RSM_OK) {
        /* Against the recent scans' fit: 1 for the first match. */
        rep->fit_ratio = loc->state.persistent.fit > 0.0f ? res.hit / loc->state.persistent.fit : 1.0f;
    }
    if (rc != RSM_OK || res.used < cfg->min_points / 2u) {
        return RSM_SCAN_LOW_SUPPORT;
    }
    if (!rep->recovered && res.hit < cfg->track_min_fit * loc->state.persistent.fit &&
        contradicts(loc, &res.pose, npts, &rep->crossing)) {
        /* Its beams pass through the map's walls: placed where the map
         * holds other walls (a robot carried, a look-alike place), or the
         * map holds a wall twice (a place mapped again after a drift). It
         * does not track and is not written (the map would soon agree with
         * a wrong pose); fitting poorly it is refused, else fused: the
         * match may still be the best there is. */
        *contradicted = 1;
        if (poor) {
            return RSM_SCAN_POOR_FIT;
        }
    }
    if (poor && cfg->refuse_poor && (ambiguous || !odometry_moved)) {
        /* Fitted far worse than recent scans and no search proved a pose,
         * while odometry stood still (the robot carried, or turning faster
         * than the scans can follow) or a search found rival poses: the
         * prediction is kept, and the scan is not written. A robot that
         * drives into new ground fits poorly too (its new points read 0,
         * its beams cross nothing the map holds), and its scans are fused
         * and written as before, or the map could not grow into a hall. */
        return RSM_SCAN_POOR_FIT;
    }
    rep->residual_m = sqrtf(res.cost);
    stage_switch(clk, RSM_STAGE_EKF);
    if (cfg->mapmatch.gate_d2 > 0.0f && res.d2 > cfg->mapmatch.gate_d2) {
        loc->ekf.rejected++;
        return RSM_SCAN_JUMP;
    }
    loc->ekf.x = res.pose;
    memcpy(loc->ekf.p, res.cov, sizeof loc->ekf.p);
    loc->ekf.updates++;
    /* A slow mean, so that a few poor scans do not lower the bar. */
    if (loc->state.persistent.fit > 0.0f) {
        loc->state.persistent.fit += 0.05f * (res.hit - loc->state.persistent.fit);
    } else {
        loc->state.persistent.fit = res.hit;
    }
    return RSM_SCAN_ACCEPTED;
}

/* Whether a match (rc its status, res the result) fits as a tracked scan
 * does: enough of the map under it, and track_min_fit of recent scans'. */
static int fits_as_tracked(const rsm_localizer_t *loc, int rc, const rsm_mapmatch_result_t *res)
{
    return rc == RSM_OK && res->used >= loc->cfg->min_points / 2u &&
           res->hit >= loc->cfg->track_min_fit * loc->state.persistent.fit;
}

/* A match's fit over recent scans' (0 when it found none). */
static float fit_ratio_of(const rsm_localizer_t *loc, int rc, const rsm_mapmatch_result_t *res)
{
    return rc == RSM_OK && loc->state.persistent.fit > 0.0f ? res->hit / loc->state.persistent.fit : 0.0f;
}

static void begin_global(rsm_localizer_t *loc, float radius_m);

/* After a gap in the scans, a scan that neither tracks where odometry put
 * it nor lies on ground the map does not hold: more than this share of
 * conflict_max of its beams passes through the map's walls (half what
 * makes a tracked scan lost: the prior after a gap says little; 0.25 of
 * the beams at the default conflict_max). Measured on the
 * first scans after the bench's 120 s gaps (docs/faults.md, "Gaps of
 * minutes"): on Intel, where odometry's one step over the gap is 2 to 15 m
 * off, 7 of 20 cross more; on ACES, where the robot comes out on ground the
 * pool no longer holds, none crosses more than 0.12; after the 15 s gaps of
 * either log none searched. */
#define GAP_CROSSING 0.5f
/* Searches after a gap that may prove nothing before the robot maps on from
 * odometry's pose: the window at 0.97 and at 0.95 of the points, then
 * twice as wide at 0.97 (rsm_global_share, rsm_global_radius). The Intel
 * runs found were found by their second; with eight, odometry alone
 * carried the others on for up to 128 scans and one came out 3.1 m off
 * instead of 0.6 m. */
#define GAP_SEARCHES 3u

/* Whether the scan after a gap (res: its match from pred, rc its status)
 * asks for a search of the map instead of being written: see GAP_CROSSING. */
static int lost_after_gap(rsm_localizer_t *loc, size_t npts, const rsm_pose_t *pred, int rc,
                          const rsm_mapmatch_result_t *res)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    float share = 0.0f;
    if (cfg->recover_m <= 0.0f || cfg->map_frozen || fits_as_tracked(loc, rc, res)) {
        return 0;
    }
    (void)contradicts(loc, rc == RSM_OK ? &res->pose : pred, npts, &share);
    return share > GAP_CROSSING * cfg->conflict_max &&
           rsm_global_check(&loc->state.persistent.map, search_bytes(loc)) == RSM_OK;
}

static rsm_outcome_t step_map(rsm_localizer_t *loc, size_t npts, int odometry_moved, float dt_s,
                              rsm_localizer_report_t *rep, stage_clock_t *clk, int *contradicted, int *carried)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    const rsm_pose_t pred = loc->ekf.x;
    const int driven = dt_s > UNSURE_GAP_S && odometry_moved && plausible_step(loc, &pred, dt_s);
    int gap;
    rsm_mapmatch_result_t res;
    rsm_mapmatch_unpin_t unpin;
    int ambiguous = 0;
    int doubted = 0;
    int poor;
    int rc;
    uint32_t passes; /* over the scan's points: the match from pred's, then doubt_step's */
    if (!loc->have_scan) {
        return RSM_SCAN_FIRST;
    }
    if (driven && loc->state.persistent.walk_apart) {
        /* Scans missing for a while, and odometry's motion over them one
         * the robot could have driven: it may have come in one piece, and
         * one step's noise stretched over metres is no prior at all (a
         * heading error of 0.2 rad per metre driven, squared: 1.3 rad
         * after 6.5 m; measured, 1 to 14 degrees). Intel and ACES with 15 s
         * gaps: a match with nothing to hold it slid 1.5 m along a
         * corridor, or turned 28 degrees on 22 points. A step no robot
         * drives in the time (a counter reset, a spike) keeps the wide
         * prior: doubt_step weighs it. */
        memcpy(loc->ekf.p, loc->state.persistent.walk_p, sizeof loc->ekf.p);
    }
    if (recovering(loc)) {
        /* A recovery in progress: a scan whose match where it was
         * predicted is not poor ends it, as it would have begun none (the
         * trouble passed: a person in front of the laser, a bump odometry
         * saw), judged first by its fit there without a descent (one
         * pass); else the rest of the scan's time goes to the recovery, the
         * robot carried by odometry meanwhile, nothing fused or written,
         * until it ends. */
        const float fit = loc->state.persistent.fit;
        uint32_t spent = RECOVER_PASS_WORK * (uint32_t)npts;
        recovery_t r;
        stage_switch(clk, RSM_STAGE_MAPMATCH);
        rep->recovering = 1u;
        if (rsm_mapmatch_fit(&loc->state.persistent.map, loc->pts, npts, &pred) >= cfg->recover_ratio * fit) {
            rsm_mapmatch_unpin_for(&cfg->mapmatch, loc->pts, npts, pred.theta, &unpin);
            res.passes = 0u;
            rc = rsm_mapmatch(&loc->state.persistent.map, &cfg->mapmatch, loc->pts, npts, &pred, loc->ekf.p, NULL,
                              &unpin, &res);
            if (rc == RSM_OK && res.used >= cfg->min_points / 2u && res.hit >= cfg->recover_ratio * fit) {
                loc->state.persistent.recovery.phase = RECOVER_IDLE;
                return settle(loc, npts, odometry_moved, rc, &res, 0, 0, rep, clk, contradicted);
            }
            spent += RECOVER_PASS_WORK * (uint32_t)npts * res.passes;
        }
        if (!loc->state.persistent.recovery.checked) {
            /* The check the scan searched had no time for, of this one
             * where it was predicted. */
            loc->state.persistent.recovery.checked = 1u;
            spent += RECOVER_CONFLICT_WORK;
            *contradicted = contradicts(loc, &pred, npts, &rep->crossing);
        }
        r = recovery_step(loc, npts, spent, 1, &res);
        if (r != RECOVERY_TAKEN) {
            return RSM_SCAN_POOR_FIT;
        }
        loc->counters.recovered++;
        rep->recovered = 1u;
        return settle(loc, npts, odometry_moved, RSM_OK, &res, 0, 0, rep, clk, contradicted);
    }
    gap = unsure(loc, dt_s); /* of the prediction, before any match moves it */
    stage_switch(clk, RSM_STAGE_MAPMATCH);
    rsm_mapmatch_unpin_for(&cfg->mapmatch, loc->pts, npts, pred.theta, &unpin);
    rep->unpinned = unpin.frac;
    if (unpin.frac > 0.0f) {
        loc->counters.unpinned++;
    }
    res.passes = 0u;
    rc = rsm_mapmatch(&loc->state.persistent.map, &cfg->mapmatch, loc->pts, npts, &pred, loc->ekf.p, NULL, &unpin,
                      &res);
    if (dt_s > UNSURE_GAP_S && !odometry_moved && cfg->recover_m > 0.0f && loc->counters.scans > 1u &&
        loc->last.track == RSM_TRACK_TRACKING &&
        !fits_as_tracked(loc, rc, &res)) {
        /* No scan for a while, odometry still, and the scan no longer
         * fits where the robot stood and tracked: it was carried (or the
         * building changed around it), as far as the time allowed. (Not
         * tracking before, the pause says nothing new: a map that does
         * not hold the place fits no better before than after; nor the
         * first scan on a loaded map.) A search near
         * the old pose would find a look-alike within its reach and
         * "prove" it against rivals there only (Intel's kidnaps: a room
         * 7 m off the truth, fitting as well as the map's own); the
         * caller reports lost at once, and the global search, if on,
         * covers the whole map. Kept at the prediction, not written. */
        rep->fit_ratio = fit_ratio_of(loc, rc, &res);
        *carried = 1;
        return RSM_SCAN_POOR_FIT;
    }
    passes = res.passes;
    rep->odometry = doubt_step(loc, npts, &pred, odometry_moved, driven, &rc, &res, &doubted, &passes);
    if (rep->odometry == RSM_ODOMETRY_CAUGHT_UP) {
        loc->counters.caught_up++;
    } else if (rep->odometry == RSM_ODOMETRY_REFUTED) {
        loc->counters.refuted++;
    } else if (rep->odometry == RSM_ODOMETRY_RECOUNTED) {
        loc->counters.recounted++;
    }
    poor = rc == RSM_OK && res.hit < cfg->recover_ratio * loc->state.persistent.fit;
    if ((poor || doubted || gap) && cfg->recover_m > 0.0f) {
        /* Far worse than recent scans, or odometry's step doubted with no
         * prediction fitting well: odometry may be off by more than any
         * basin. A recovery searches (recovery_step): the smallest
         * correction that explains the scan first, a turn misjudged (every
         * heading within recover_rad), then the position within a coarse
         * cell, and only if neither fits a shift up to recover_m (a bump, a
         * kidnap); along a corridor a shifted pose can fit about as well as
         * the right one. Begun here, with this scan's readings and what is
         * left of its time (recover_budget, after its matches), run on in
         * the scans that follow, the scan kept at its prediction. Not for a
         * scan that found too little map to match: the search would find
         * no more, and it is written at the prediction (new ground). */
        if (cfg->recover_budget == 0u) {
            /* The smallest correction first: every heading within
             * recover_rad and the position within one coarse cell, and only
             * if that does not fit, a shift up to recover_m. An ambiguous
             * near search is not widened: a farther pose would have that
             * same rival, and the wider search might not see it. */
            const float near_m = rsm_tmap_cell(&loc->state.persistent.map, (uint32_t)cfg->tmap.levels - 1u);
            recovery_t r;
            loc->counters.searches++;
            rep->recovering = 1u;
            r = recover(loc, npts, &pred, near_m < cfg->recover_m ? near_m : cfg->recover_m, &res);
            if (r == RECOVERY_NONE && near_m < cfg->recover_m) {
                r = recover(loc, npts, &pred, cfg->recover_m, &res);
            }
            if (r == RECOVERY_TAKEN) {
                loc->counters.recovered++;
                rep->recovered = 1u;
                poor = 0;
            } else if (r == RECOVERY_AMBIGUOUS) {
                loc->counters.ambiguous++;
                ambiguous = 1;
            }
        } else if (recovery_may_begin(loc, &pred) && rc == RSM_OK && res.used >= cfg->min_points / 2u) {
            rsm_recovery_t *rr = &loc->state.persistent.recovery;
            recovery_t r;
            loc->counters.searches++;
            rep->recovering = 1u;
            recovery_begin(loc, npts, &pred, &res);
            /* What this scan's matches took. */
            r = recovery_step(loc, npts, RECOVER_PASS_WORK * (uint32_t)npts * passes, 0, &res);
            if (recovering(loc)) {
                /* Kept at its prediction (its poor match is no better a
                 * guess). Its match is checked against the map's walls here
                 * when the time allows, else the next scan where it was
                 * predicted: one that contradicts the map is lost at once
                 * (with global_when_lost the global search takes over; else
                 * the recovery runs on). */
                rr->checked = 0u;
                rep->fit_ratio = fit_ratio_of(loc, rc, &res);
                if (RECOVER_PASS_WORK * (uint32_t)npts * passes + RECOVER_FIRST_WORK + RECOVER_CONFLICT_WORK <=
                    cfg->recover_budget) {
                    rr->checked = 1u;
                    *contradicted = contradicts(loc, &res.pose, npts, &rep->crossing);
                }
                return RSM_SCAN_POOR_FIT;
            }
            if (r == RECOVERY_TAKEN) {
                loc->counters.recovered++;
                rep->recovered = 1u;
                poor = 0;
            } else if (r == RECOVERY_AMBIGUOUS) {
                ambiguous = 1;
            }
        }
    }
    if (gap && driven && !rep->recovered && lost_after_gap(loc, npts, &pred, rc, &res)) {
        /* Odometry over a gap of minutes comes in one step that can be
         * metres and tens of degrees off (Intel: its drift of 3 degrees a
         * metre over a path that the step's chord does not tell), and the
         * recovery's reach is a metre: written here, the scan would begin a
         * second copy of the place. Searched for instead, nothing written
         * meanwhile, within twice the step's length and recover_m (a step
         * of the right length turned by any angle ends no farther off). */
        const rsm_pose_t d = rsm_pose_between(&loc->state.persistent.anchor, &pred);
        begin_global(loc, 2.0f * sqrtf(d.x * d.x + d.y * d.y) + cfg->recover_m);
        loc->state.persistent.global.give_up = GAP_SEARCHES;
        rep->fit_ratio = fit_ratio_of(loc, rc, &res);
        *carried = 1;
        return RSM_SCAN_POOR_FIT;
    }
    return settle(loc, npts, odometry_moved, rc, &res, poor, ambiguous, rep, clk, contradicted);
}

/* The walls' grid is learnt from this many scans with walls enough
 * (WALL_MIN_SUPPORT_M of them), tracking from the start: their heading is
 * the map's own then, before any drift. */
#define WALL_REF_SCANS 20u
#define WALL_MIN_SUPPORT_M 2.0f
/* ... and only where that much of the scan's straight walls run along the
 * grid: in a building without one, directions spread evenly put a few
 * stretches in any window, whose mean would hold the heading where it is. */
#define WALL_MIN_SHARE 0.25f
/* wall_sigma_rad is for this much of the stretches seen (they overlap:
 * about half as much wall). */
#define WALL_SIGMA_SUPPORT_M 5.0f

/* The walls' grid (wallgrid.h): learnt from the first scans, then a
 * heading measurement for every scan that tracks and sees walls enough
 * along it. The grid's directions are found around the expected one, two
 * steps narrowing to wall_window_rad from no window at all for the very
 * first scan, which has nothing to expect. */
static void wall_heading(rsm_localizer_t *loc, size_t npts)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    const float theta = loc->ekf.x.theta;
    const float window = cfg->wall_window_rad;
    float expect;
    float dir;
    float support;
    float straight;
    float delta;
    if (cfg->wall_sigma_rad <= 0.0f) {
        return;
    }
    if (loc->state.persistent.wall_scans == 0u) {
        rsm_wallgrid_direction(loc->pts, npts, 0.0f, RSM_PI, &expect, &support, &straight);
        rsm_wallgrid_direction(loc->pts, npts, expect, 4.0f * window, &expect, &support, &straight);
    } else {
        expect = loc->state.persistent.wall_ref - theta;
    }
    rsm_wallgrid_direction(loc->pts, npts, expect, window, &dir, &support, &straight);
    if (support < WALL_MIN_SUPPORT_M || support < WALL_MIN_SHARE * straight) {
        return;
    }
    if (loc->state.persistent.wall_scans < WALL_REF_SCANS) {
        const float world = 4.0f * (dir + theta);
        loc->state.persistent.wall_c += support * rsm_cosf(world);
        loc->state.persistent.wall_s += support * rsm_sinf(world);
        loc->state.persistent.wall_ref =
            0.25f * rsm_atan2f(loc->state.persistent.wall_s, loc->state.persistent.wall_c);
        loc->state.persistent.wall_scans++;
        return;
    }
    delta = rsm_wallgrid_diff(loc->state.persistent.wall_ref, dir + theta);
    {
        const float scale = support < WALL_SIGMA_SUPPORT_M ? WALL_SIGMA_SUPPORT_M / support : 1.0f;
        /* Softly: a pull half the window off counts a quarter as much, one
         * at its edge a twenty-fifth. Drift is pulled back while small,
         * and a wing built a couple of degrees off the grid (ACES has
         * some) pulls little. */
        const float soft = 1.0f + (delta / (0.5f * window)) * (delta / (0.5f * window));
        (void)rsm_ekf_pull_heading(&loc->ekf, delta, cfg->wall_sigma_rad * cfg->wall_sigma_rad * scale * soft * soft);
    }
}

/* Starts writing the scan into the persistent map at est once the robot has
 * moved far enough since the last write (or for the first scan); the write
 * then runs over this and the next scans (tmap.write_cells), from loc->frame.world,
 * which nothing else writes meanwhile. A write still running when the next
 * one is due is finished first. Returns 1 when a scan that found too
 * little map to match (unmatched) was not written because it contradicts
 * the map, else 0. */
static int write_tmap(rsm_localizer_t *loc, const rsm_pose_t *est, size_t npts, int first, int unmatched,
                      rsm_localizer_report_t *rep)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    rsm_tmap_t *map = &loc->state.persistent.map;
    rsm_global_t *g = &loc->state.persistent.global;
    const rsm_pose_t d = rsm_pose_between(&loc->state.persistent.written, est);
    uint8_t isolated[(RSM_MAX_BEAMS + 7) / 8];
    rsm_point_t origin;
    int keep;
    if (!first && sqrtf(d.x * d.x + d.y * d.y) < cfg->map_update_m && fabsf(d.theta) < cfg->map_update_rad) {
        return 0;
    }
    if (unmatched && contradicts(loc, est, npts, &rep->crossing)) {
        /* Too little map to match, and its beams pass through walls the
         * map holds: not new ground but a wrong pose, and written the scan
         * would make the map agree with it within a few writes. */
        return 1;
    }
    (void)rsm_tmap_write_run(map, loc->frame.world, 0u);
    /* The scan takes the memory of the global search's grids, unless the
     * caller lent the search its own: then grids that stand are kept
     * through the write (a search after tracking with updates on need not
     * build them again). */
    keep = loc->state.persistent.search_mem != NULL && rsm_global_can_keep(g, map);
    if (!keep) {
        g->cached = 0u;
    }
    to_world(loc, est, npts);
    origin.x = cfg->laser_mount.x;
    origin.y = cfg->laser_mount.y;
    origin = rsm_pose_apply(est, &origin);
    /* With the isolation rule on (off by default: it costs ACES, docs/map.md)
     * returns no neighbour confirms stay out of the map (they still count
     * in matching, where a map that holds only confirmed walls outvotes
     * them): a map keeps what it is given for minutes, and phantom returns
     * would take its memory and blur its walls. */
    if (rsm_points_isolated(loc->frame.world, npts, &origin, &cfg->isolation, isolated) > 0u) {
        size_t k;
        size_t kept = 0;
        for (k = 0; k < npts; ++k) {
            if (rsm_bit_get(isolated, k)) {
                loc->counters.unconfirmed++;
            } else {
                loc->frame.world[kept++] = loc->frame.world[k];
            }
        }
        npts = kept;
    }
    if (rsm_tmap_write_begin(map, &origin, loc->frame.world, npts) == RSM_OK) {
        loc->state.persistent.written = *est;
        if (keep) {
            rsm_global_keep(g, search_grid(loc), map, loc->frame.world, npts);
        }
    }
    return 0;
}

static rsm_outcome_t step_icp(rsm_localizer_t *loc, size_t npts, rsm_localizer_report_t *rep, stage_clock_t *clk)
{
    const rsm_pose_t pred = loc->ekf.x;
    rsm_icp_result_t res;
    float r[9];
    int rc;
    rsm_outcome_t out;
    if (!loc->have_scan) {
        return RSM_SCAN_FIRST;
    }
    stage_switch(clk, RSM_STAGE_ICP);
    rc = rsm_icp_align(&loc->state.icp, loc->pts, npts, &pred, &res);
    rep->iterations = res.iterations;
    rep->inliers = res.pairs;
    if (rc != RSM_OK) {
        return RSM_SCAN_LOW_SUPPORT;
    }
    rep->residual_m = res.rms_m;
    stage_switch(clk, RSM_STAGE_EKF);
    measurement_noise(loc->cfg, res.rms_m, res.pairs, 4.0f, r);
    out = fuse(loc, &res.pose, r, rep);
    return out;
}

/* A global search is to begin at the next usable scan, over positions
 * within radius_m of the estimate then (0: the whole map). */
static void begin_global(rsm_localizer_t *loc, float radius_m)
{
    /* The search takes the memory a recovery keeps its readings in. */
    loc->state.persistent.recovery.phase = RECOVER_IDLE;
    loc->state.persistent.global.phase = RSM_GLOBAL_PENDING;
    loc->state.persistent.global.unproven = 0u;
    loc->state.persistent.global.pending = 0u;
    loc->state.persistent.global.radius_m = radius_m;
    loc->state.persistent.global.give_up = 0u;
    if (!(loc->state.persistent.map_fit > 0.0f)) {
        /* A map made in this run: its scans' recent fit is the bar. */
        loc->state.persistent.map_fit = loc->state.persistent.fit;
    }
}

int rsm_localizer_global(rsm_localizer_t *loc)
{
    return rsm_localizer_global_near(loc, 0.0f);
}

int rsm_localizer_global_near(rsm_localizer_t *loc, float radius_m)
{
    const rsm_tmap_t *map;
    int rc;
    if (!ready(loc) || !(radius_m >= 0.0f && radius_m <= 1.0e6f)) {
        return RSM_ERR_INVAL;
    }
    if (loc->cfg->method != RSM_METHOD_MAP) {
        return RSM_ERR_NOSYS;
    }
    map = &loc->state.persistent.map;
    if ((rc = rsm_global_check(map, search_bytes(loc))) != RSM_OK) {
        return rc;
    }
    begin_global(loc, radius_m);
    loc->poor_run = loc->cfg->lost_scans;
    loc->last.track = RSM_TRACK_LOST;
    return RSM_OK;
}

int rsm_localizer_searching(const rsm_localizer_t *loc)
{
    return ready(loc) && global_running(loc);
}

int rsm_localizer_set_search_memory(rsm_localizer_t *loc, void *mem, size_t bytes)
{
    rsm_global_t *g;
    if (!ready(loc) || (mem == NULL) != (bytes == 0u) || (mem != NULL && bytes < (size_t)RSM_GLOBAL_GRID_BYTES)) {
        return RSM_ERR_INVAL;
    }
    if (loc->cfg->method != RSM_METHOD_MAP) {
        return RSM_ERR_NOSYS;
    }
    g = &loc->state.persistent.global;
    if (mem == NULL) {
        /* Back to the shared memory: the write in progress, if any, ends
         * before the grids take it. */
        (void)rsm_tmap_write_run(&loc->state.persistent.map, loc->frame.world, 0u);
    }
    loc->state.persistent.search_mem = (uint8_t *)mem;
    loc->state.persistent.search_bytes =
        bytes < (size_t)RSM_GLOBAL_MAX_GRID_BYTES ? (uint32_t)bytes : (uint32_t)RSM_GLOBAL_MAX_GRID_BYTES;
    g->cached = 0u;
    if (global_running(loc)) {
        g->phase = RSM_GLOBAL_PENDING;
    }
    /* Built now, as a map load does (an empty map has none to build). */
    (void)rsm_global_prepare(g, search_grid(loc), search_bytes(loc), &loc->state.persistent.map, NULL);
    return RSM_OK;
}

/* The fit a proven place must reach a share of: the map's own (saved with
 * it), else the recent scans' as the search began, else 1. */
static float bar_fit(const rsm_localizer_t *loc)
{
    const float f = loc->state.persistent.map_fit;
    return f > 0.0f ? f : 1.0f;
}

/* The fit a search's winner must reach: global_min_fit of the map's own,
 * or global_crowded_fit when at least as many places reached the search's
 * bar unkept as it kept (rsm_global_fit_share). Measured on the bench's
 * global starts: the winners of such searches that were 33 and 43 m off
 * on ACES fitted 0.85 and 0.86 of the map's own, the right ones 0.90 to 1.08 (ACES) and 0.87
 * to 1.03 (Intel): docs/globalsearch.md, "Crowded searches". */
static float win_fit(const rsm_localizer_t *loc)
{
    return rsm_global_fit_share(&loc->state.persistent.global, loc->cfg->global_min_fit,
                                loc->cfg->global_crowded_fit) *
           bar_fit(loc);
}

/* What the proof's steps cost, in the search's work (rsm_global_run's
 * units: about 18 M4 instructions), so that global_budget spreads the
 * proof over scans too: a kept pose's descent with the kept share of a
 * scan (about 170 000 M4 instructions), and the winner's with the whole
 * scan at hand, a near search and up to two descents (up to about 720 000:
 * always a scan of its own). Measured on the M4 (docs/globalsearch.md,
 * "What a scan costs on the M4"). */
#define PROVE_WORK 9500u
#define WIN_WORK 40000u
/* A search's beginning (the scan's points and wall directions, the
 * grids' layout) costs about this much (about 200 000 instructions). */
#define BEGIN_WORK 11000u
/* Proofs of the same kept poses, each with a scan that follows, while the
 * best fits well but a rival is too close or the scan does not pin it,
 * before a new search; each once the robot has moved this far or turned
 * this much since the last. */
#define PROVE_ROUNDS 4u
/* The winner is looked for again around where odometry carried it (a near
 * search: most of a descent's cost) only when its reach is this much
 * beyond two cells: within it, the descent from the wide prior finds it. */
#define NEAR_FROM_M 0.1f

/* Around each point, the tiles within this of it come back from the store
 * before a match (and two cells more on every level): a few centimetres
 * of motion the prediction missed. */
#define FETCH_MARGIN_M 0.05f

/* Keeps a share of this scan's readings (taken evenly) for the proof, with
 * the estimate now: every kept pose is descended with the same scan. */
static void keep_seen(rsm_localizer_t *loc, size_t npts)
{
    rsm_global_t *g = &loc->state.persistent.global;
    const size_t cap = sizeof g->pts / sizeof g->pts[0];
    const size_t n = npts < cap ? npts : cap;
    size_t k;
    for (k = 0; k < n; ++k) {
        g->pts[k] = loc->pts[k * npts / n];
    }
    g->nseen = (uint32_t)n;
    g->seen_at = loc->ekf.x;
}

/* Kept pose k descended with the kept scan, from its cell (so under a
 * prior of two cells and two heading steps): its fit and pose (as of that
 * scan) to g->hit[k] and g->end[k]. */
static void prove_one(rsm_localizer_t *loc, uint32_t k)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    rsm_global_t *g = &loc->state.persistent.global;
    const rsm_tmap_t *map = &loc->state.persistent.map;
    const float cell = rsm_tmap_cell(map, g->level);
    float wide[9];
    rsm_mapmatch_result_t res;
    memset(wide, 0, sizeof wide);
    wide[0] = wide[4] = 4.0f * cell * cell;
    wide[8] = 4.0f * g->step_rad * g->step_rad;
    g->hit[k] = -1.0f;
    g->end[k] = g->cand[k].pose;
    (void)rsm_tmap_fetch(&loc->state.persistent.map, &g->cand[k].pose, g->pts, g->nseen, 2.0f * cell);
    if (rsm_mapmatch(map, &cfg->mapmatch, g->pts, g->nseen, &g->cand[k].pose, wide, &g->cand[k].pose, NULL, &res) ==
        RSM_OK) {
        g->hit[k] = res.hit;
        g->end[k] = res.pose;
    }
}

/* Kept pose k as descended, carried by odometry to this scan. */
static rsm_pose_t proved_now(const rsm_localizer_t *loc, uint32_t k)
{
    const rsm_global_t *g = &loc->state.persistent.global;
    const rsm_pose_t since = rsm_pose_between(&g->seen_at, &loc->ekf.x);
    return rsm_pose_compose(&g->end[k], &since);
}

/* The kept poses' verdict once each is descended with the kept scan
 * (prove_one): the best is the winner when its fit reaches global_min_fit
 * of the map's (saved with it) and beats every pose a doubt away from it by
 * recover_margin (all fits of the same scan). 1: a winner, in *win; 0: a
 * rival too close; -1: the best fits too poorly. */
static int prove_verdict(const rsm_localizer_t *loc, uint32_t *win)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    /* A place the map holds fits about as well as the map's own scans did
     * (saved with it): a wrong place in a building of look-alike rooms fits
     * half as well (measured on ACES: 0.41 to 0.44 against 0.86). */
    return rsm_global_verdict(&loc->state.persistent.global, win_fit(loc), cfg->recover_margin, cfg->doubt_m,
                              cfg->doubt_rad, win);
}

/* How far odometry may have drifted over the motion moved (since a kept
 * scan): two of the search's cells and heading steps, and 10 % of the
 * travel and 0.05 rad a metre or radian, within the recovery search's
 * reach. */
static void drift_reach(const rsm_localizer_t *loc, const rsm_pose_t *moved, float *reach_m, float *reach_rad)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    const rsm_global_t *g = &loc->state.persistent.global;
    const float cell = rsm_tmap_cell(&loc->state.persistent.map, g->level);
    const float travelled = sqrtf(moved->x * moved->x + moved->y * moved->y);
    float m = 2.0f * cell + 0.1f * travelled;
    float rad = 2.0f * g->step_rad + 0.05f * (travelled + fabsf(moved->theta));
    m = m < cfg->recover_m ? m : cfg->recover_m;
    rad = rad < cfg->recover_rad ? rad : cfg->recover_rad;
    *reach_m = m > 2.0f * cell ? m : 2.0f * cell;
    *reach_rad = rad;
}

/* The winner with the scan at hand: carried forward by odometry's motion
 * since the kept scan, looked for again around there when the robot drove
 * far meanwhile (the search was spread over scans), and descended under a
 * prior as wide as odometry's drift. Proven when it fits this scan as the
 * verdict asked of the kept one and the scan pins it. 1: proven, its match
 * in *out; 0: not (*out then undefined). */
static int prove_win(rsm_localizer_t *loc, uint32_t win, size_t npts, rsm_mapmatch_result_t *out)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    rsm_global_t *g = &loc->state.persistent.global;
    const rsm_tmap_t *map = &loc->state.persistent.map;
    const rsm_pose_t moved = rsm_pose_between(&g->seen_at, &loc->ekf.x);
    const float cell = rsm_tmap_cell(map, g->level);
    float reach_m;
    float reach_rad;
    float wide[9];
    rsm_pose_t start = proved_now(loc, win);
    rsm_pose_t near[2];
    rsm_mapmatch_result_t *res = out;
    rsm_mapmatch_result_t r2;
    rsm_mapmatch_result_t other;
    int n = 0;
    int m;
    int have = 0;
    int have_other = 0;
    drift_reach(loc, &moved, &reach_m, &reach_rad);
    memset(wide, 0, sizeof wide);
    wide[0] = wide[4] = reach_m * reach_m;
    wide[8] = reach_rad * reach_rad;
    (void)rsm_tmap_fetch(&loc->state.persistent.map, &start, loc->pts, npts, reach_m);
    if (reach_m > 2.0f * cell + NEAR_FROM_M) {
        /* Carried far (odometry's drift past the descent's basin): look
         * for it again around where odometry puts it. */
        n = rsm_mapmatch_search(map, &cfg->mapmatch, loc->pts, npts, &start, reach_m, reach_rad, near, 2u,
                                (size_t)RSM_GLOBAL_POINTS);
    }
    if (n <= 0) {
        near[0] = start;
        n = 1;
    }
    for (m = 0; m < n; ++m) {
        if (rsm_mapmatch(map, &cfg->mapmatch, loc->pts, npts, &start, wide, &near[m], NULL, &r2) != RSM_OK) {
            continue;
        }
        if (!have || r2.hit > res->hit) {
            other = *res;
            have_other = have;
            *res = r2;
            have = 1;
        } else {
            other = r2;
            have_other = 1;
        }
    }
    /* Two places within odometry's drift, the better not ahead by
     * recover_margin: a look-alike along the corridor the robot drove
     * since the kept scan, which only the kept scan's verdict ruled out
     * (measured on ACES: an office 0.76 m on fitted 0.8617 against the
     * true place's 0.8613). In doubt until the robot moves on. */
    if (have && have_other && beyond_doubt(cfg, &other.pose, &res->pose) &&
        !(res->hit > other.hit * (1.0f + cfg->recover_margin))) {
        return 0;
    }
    /* This scan must fit as the verdict asked of the kept one: a winner
     * that only the kept scan's share of readings bore out is no proof
     * (measured on an Intel kidnap: a pose 9 m off fitted the share 0.80
     * and this scan 0.69 of the map's own 0.93). (Asking
     * global_crowded_fit of every winner's whole scan kept an ACES corridor
     * 18 m from the truth, at 0.81, from being proven, but no scan with a
     * tenth of its readings unmatched is then proven anywhere.) */
    if (!have || !(res->hit >= win_fit(loc))) {
        return 0;
    }
    /* Its covariance says what the scan pins (under a prior at least two
     * cells wide: as wide as the one it once had a descent of its own
     * for, or wider). */
    {
        /* A pose the scan does not pin (along a bare corridor, its
         * position is the search lattice's, not the scan's: measured on
         * ACES, 0.3 to 0.6 m off) is no proof: its position's largest
         * standard deviation must be within half a cell. */
        const float a = res->cov[0];
        const float d = res->cov[4];
        const float b = res->cov[1];
        const float largest = 0.5f * (a + d) + sqrtf(0.25f * (a - d) * (a - d) + b * b);
        if (!(largest <= 0.25f * cell * cell)) {
            return 0;
        }
    }
    return 1;
}

/* Whether a proven winner (at pose) may be taken (rsm_global_take): a
 * crowded search's only once a later search proves the same place, within
 * odometry's drift since (drift_reach). */
static int winner_taken(rsm_localizer_t *loc, const rsm_pose_t *pose)
{
    rsm_global_t *g = &loc->state.persistent.global;
    const rsm_pose_t moved = rsm_pose_between(&g->pending_at, &loc->ekf.x);
    float reach_m;
    float reach_rad;
    drift_reach(loc, &moved, &reach_m, &reach_rad);
    return rsm_global_take(g, pose, &loc->ekf.x, reach_m, reach_rad);
}

/* Takes a proven winner's match (prove_win) into the filter. */
static void take_win(rsm_localizer_t *loc, const rsm_mapmatch_result_t *res)
{
    loc->ekf.x = res->pose;
    memcpy(loc->ekf.p, res->cov, sizeof loc->ekf.p);
    loc->ekf.updates++;
    loc->state.persistent.fit = res->hit;
    loc->state.persistent.written = res->pose;
}

/* A scan while a global search is under way (RSM_METHOD_MAP). */
/* A scan the search took and placed nothing with: its reads counted. */
static rsm_outcome_t searching(rsm_localizer_t *loc, rsm_localizer_report_t *rep, uint32_t used)
{
    rep->search_work = used;
    loc->counters.global_work += used;
    return RSM_SCAN_SEARCHING;
}

static rsm_outcome_t step_global(rsm_localizer_t *loc, size_t npts, rsm_localizer_report_t *rep)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    rsm_global_t *g = &loc->state.persistent.global;
    const rsm_tmap_t *map = &loc->state.persistent.map;
    const uint32_t budget = cfg->global_budget;
    uint32_t used = 0;
    if (g->phase == RSM_GLOBAL_PROVING && g->proved == 0u && g->rounds > 0u) {
        /* A proof left in doubt is made again only from a new view: once
         * the robot has moved on since (a stationary robot sees the same
         * corridor, the same look-alike room). */
        const rsm_pose_t d = rsm_pose_between(&g->seen_at, &loc->ekf.x);
        uint32_t k;
        if (sqrtf(d.x * d.x + d.y * d.y) < PROVE_AGAIN_M && fabsf(d.theta) < PROVE_AGAIN_RAD) {
            return RSM_SCAN_SEARCHING;
        }
        /* The poses, carried by odometry to this scan, are descended with
         * it. */
        for (k = 0; k < g->found; ++k) {
            g->cand[k].pose = rsm_pose_compose(&g->cand[k].pose, &d);
        }
        keep_seen(loc, npts);
    }
    if (g->phase == RSM_GLOBAL_PROVING) {
        /* The kept poses first, as many a scan as global_budget pays for
         * (at least one; all with no budget); the winner with a scan of
         * its own (with a budget: its near search and descents cost about
         * as much as a scan may). */
        int verdict = 1;
        uint32_t win = 0;
        while (g->proved < g->found && (budget == 0u || used == 0u || used + PROVE_WORK <= budget)) {
            prove_one(loc, g->proved++);
            used += PROVE_WORK;
        }
        if (g->proved == g->found) {
            verdict = prove_verdict(loc, &win);
            if (verdict > 0 && (budget == 0u || used == 0u)) {
                rsm_mapmatch_result_t won;
                used += WIN_WORK;
                if (prove_win(loc, win, npts, &won)) {
                    if (!winner_taken(loc, &won.pose)) {
                        /* Crowded, and not yet proven by a second search:
                         * searched again at the same bar, from the next
                         * scan. */
                        loc->counters.global_ambiguous++;
                        g->phase = RSM_GLOBAL_PENDING;
                        return searching(loc, rep, used);
                    }
                    take_win(loc, &won);
                    g->phase = RSM_GLOBAL_IDLE;
                    loc->counters.global_found++;
                    rep->recovered = 1u;
                    rep->fit_ratio = 1.0f;
                    rep->measured = loc->ekf.x;
                    rep->search_work = used;
                    loc->counters.global_work += used;
                    return RSM_SCAN_ACCEPTED;
                }
                /* It fitted the kept scan, not this one, or this one does
                 * not pin it: in doubt. */
                verdict = 0;
            } else if (verdict > 0) {
                /* The winner's turn comes with the next scan. */
                verdict = 2;
            }
        }
        if (g->proved < g->found || verdict == 2) {
            return searching(loc, rep, used);
        }
        if (verdict == 0 && g->rounds < PROVE_ROUNDS) {
            /* Left in doubt, though the best fits: the same poses, as
             * descended and carried here, are proven again with this scan
             * (the robot moved on: a rival along a corridor or in a
             * look-alike room falls behind), before any new search. */
            uint32_t k;
            rsm_global_add_round(g, win_fit(loc));
            for (k = 0; k < g->found; ++k) {
                g->cand[k].pose = proved_now(loc, k);
            }
            /* The poses now stand for this scan; the next round's kept
             * scan is taken once the robot has moved. */
            g->seen_at = loc->ekf.x;
            g->proved = 0;
            g->rounds++;
            return searching(loc, rep, used);
        }
        /* Not proven: another view may settle it, searched with what is
         * left of this scan's budget (or from the next scan). */
        loc->counters.global_ambiguous++;
        g->unproven++;
        g->phase = RSM_GLOBAL_PENDING;
        if (g->give_up > 0u && g->unproven >= g->give_up) {
            /* A search after a gap that proved nothing: the robot maps on
             * from odometry's pose, as it did before the search. */
            g->phase = RSM_GLOBAL_IDLE;
            return searching(loc, rep, used);
        }
        if (budget > 0u && used + BEGIN_WORK >= budget) {
            return searching(loc, rep, used);
        }
    }
    if (g->phase == RSM_GLOBAL_PENDING) {
        /* The bar falls after searches that proved nothing
         * (rsm_global_share). */
        const float share = rsm_global_share(map, g->radius_m, g->unproven, cfg->global_min_share);
        /* The grids take the memory of the scan a map write reads: the
         * write in progress, if any, ends first. */
        (void)rsm_tmap_write_run(&loc->state.persistent.map, loc->frame.world, 0u);
        /* The levels it reads whole: what tracking or a proof let go into
         * the store comes back first (a frozen map then keeps its grids),
         * within the scans' budget (on ACES a thousand tiles may come
         * back). With nothing let go since they last came back, nothing is
         * looked up (on ACES that look-up alone took a scan's budget). */
        if (loc->state.persistent.map.store != NULL &&
            (g->taken_back == 0u || g->back_stored != loc->state.persistent.map.counters.stored)) {
            int more = 0;
            if (budget > 0u && used > 0u) {
                /* With a scan of its own: looking the levels' places up
                 * costs thousands of reads beside the tiles taken. */
                return searching(loc, rep, used);
            }
            used += rsm_global_take_back(&loc->state.persistent.map, budget, &more);
            if (more > 0) {
                return searching(loc, rep, used);
            }
            /* Whole, unless the pool had no slot for some (then looked up
             * again by the next search). */
            g->taken_back = more == 0 ? 1u : 0u;
            g->back_stored = loc->state.persistent.map.counters.stored;
            if (budget > 0u && used + BEGIN_WORK >= budget) {
                return searching(loc, rep, used);
            }
        }
        if (rsm_global_begin(g, search_grid(loc), search_bytes(loc), map, loc->pts, npts, &loc->ekf.x, share) !=
            RSM_OK) {
            /* The map no longer fits the search (written since it was
             * asked for): the search is given up, counted as unproven. */
            loc->counters.global_ambiguous++;
            g->phase = RSM_GLOBAL_IDLE;
            return searching(loc, rep, used);
        }
        if (g->radius_m > 0.0f) {
            /* Near the estimate, in a window that doubles with every
             * second search that proved nothing, to the whole map. */
            rsm_global_window(g, search_grid(loc), map, loc->ekf.x.x, loc->ekf.x.y,
                              rsm_global_radius(g->radius_m, g->unproven));
        }
        loc->counters.global_searches++;
        g->phase = RSM_GLOBAL_RUNNING;
        used += BEGIN_WORK;
        if (budget > 0u && used >= budget) {
            return searching(loc, rep, used);
        }
    }
    if (rsm_global_run(g, search_grid(loc), map, budget > 0u ? budget - used : 0u, &used) == 0) {
        g->phase = RSM_GLOBAL_PROVING;
        g->proved = 0;
        g->rounds = 0;
        if (g->pending && rsm_global_crowded(g)) {
            /* A crowded search after one whose winner waits (winner_taken):
             * that winner, carried to the scan searched, is weighed against
             * this search's poses too, whether or not this one kept it. */
            const rsm_pose_t then = rsm_global_pending_carried(g, &g->seen_at);
            rsm_global_weigh_also(g, map, &then);
        }
    }
    return searching(loc, rep, used);
}

/* The tracking state after a scan: a scan tracks when it was fused and,
 * matched against the persistent map, fitted about as well as recent scans
 * (track_min_fit of their fit; a proven search's winner does) without its
 * beams passing through the map's walls (conflict_max), or it started the
 * map; odometry alone is not checked. Counts the scans in a row that did
 * not; one that contradicts the map counts as lost_scans of them: the
 * robot is elsewhere, and with global_when_lost the search should not
 * wait (on Intel's kidnaps with the map written, found again after a
 * median 73 scans instead of 104). */
static rsm_track_t track_state(rsm_localizer_t *loc, rsm_outcome_t outcome, const rsm_localizer_report_t *rep,
                               int contradicted)
{
    const rsm_localizer_config_t *cfg = loc->cfg;
    int tracks = outcome == RSM_SCAN_FIRST || outcome == RSM_SCAN_ODOMETRY || outcome == RSM_SCAN_ACCEPTED;
    if (outcome == RSM_SCAN_ACCEPTED && cfg->method == RSM_METHOD_MAP) {
        tracks = rep->fit_ratio >= cfg->track_min_fit && !contradicted;
    }
    if (tracks) {
        loc->poor_run = 0u;
        return RSM_TRACK_TRACKING;
    }
    if (contradicted && loc->poor_run < cfg->lost_scans) {
        loc->poor_run = cfg->lost_scans - 1u;
    }
    if (loc->poor_run < UINT32_MAX) {
        loc->poor_run++;
    }
    return loc->poor_run >= cfg->lost_scans ? RSM_TRACK_LOST : RSM_TRACK_UNCERTAIN;
}

int rsm_localizer_scan_checked(rsm_localizer_t *loc, const rsm_scan_t *scan, size_t scan_size,
                               unsigned long fingerprint, rsm_localizer_report_t *rep)
{
    rsm_localizer_report_t local;
    stage_clock_t clk;
    rsm_outcome_t outcome;
    rsm_pose_t est;
    size_t npts;
    float prior_var;
    int odometry_moved;
    int global_taken = 0;
    int contradicted = 0;
    int carried = 0;
    rsm_pose_t pred;
    int n;
    if (!RSM_SAME_BUILD(rsm_scan_t, scan_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (rep == NULL) {
        rep = &local;
    }
    memset(rep, 0, sizeof *rep);
    if (!ready(loc) || scan == NULL || scan->count > RSM_MAX_BEAMS) {
        return RSM_ERR_INVAL;
    }
    stage_begin(&clk, loc->cfg, rep);
    loc->counters.scans++;
    if (loc->have_scan && scan->stamp_us < loc->last_stamp_us) {
        loc->counters.outcome[RSM_SCAN_OUT_OF_ORDER]++;
        rep->outcome = RSM_SCAN_OUT_OF_ORDER;
        rep->track = loc->last.track;
        rep->pose = loc->ekf.x;
        reported_cov(loc, rep->cov);
        stage_end(&clk);
        return RSM_ERR_ORDER;
    }
    if (loc->have_scan && loc->counters.motions == loc->motions_at_scan) {
        /* No odometry since the last scan: the robot may still have moved. */
        static const rsm_motion_t still = {0.0f, 0.0f, 0.0f};
        (void)rsm_localizer_motion(loc, &still);
    }
    loc->motions_at_scan = loc->counters.motions;
    odometry_moved = 0;
    pred = loc->ekf.x;
    if (loc->cfg->method == RSM_METHOD_MAP) {
        odometry_moved = moved(&loc->state.persistent.anchor, &loc->ekf.x);
        if (!odometry_moved && loc->have_scan && refuting(loc->cfg)) {
            /* Odometry stands still: the robot may have stopped, or odometry
             * stalled while it still moves (it will catch up: doubt_step),
             * as fast as it last did (odometry's last step, or what the last
             * scan found while odometry stood still). The prediction stays,
             * but no surer than that step's size, so that the scan can show
             * it; a robot that stopped soon shows no step. */
            const rsm_pose_t *l = &loc->state.persistent.last_step;
            const float d2 = l->x * l->x + l->y * l->y;
            const float q[9] = {d2, 0.0f, 0.0f, 0.0f, d2, 0.0f, 0.0f, 0.0f, l->theta * l->theta};
            static const rsm_motion_t none = {0.0f, 0.0f, 0.0f};
            (void)rsm_ekf_predict(&loc->ekf, &none, q);
        }
    }
    prior_var = loc->ekf.p[8];
    n = rsm_scan_to_points_cached(scan, &loc->cfg->limits, &loc->trig, loc->pts, RSM_MAX_BEAMS, &loc->counters.drops);
    npts = n > 0 ? (size_t)n : 0u;
    if (loc->cfg->method == RSM_METHOD_MAP) {
        npts = drop_occluded(loc, npts);
    }
    apply_mount(loc, npts);
    rep->points = (uint32_t)npts;
    if (loc->cfg->method == RSM_METHOD_MAP && loc->have_scan && npts >= loc->cfg->min_points &&
        !global_running(loc)) {
        /* Places the pool let go come back from the store before the
         * match reads them (none: nothing to do). */
        (void)rsm_tmap_fetch(&loc->state.persistent.map, &loc->ekf.x, loc->pts, npts, FETCH_MARGIN_M);
    }
    if (npts < loc->cfg->min_points) {
        outcome = RSM_SCAN_FEW_POINTS;
    } else if (loc->cfg->method == RSM_METHOD_ODOMETRY) {
        outcome = RSM_SCAN_ODOMETRY;
    } else if (loc->cfg->method == RSM_METHOD_ICP) {
        outcome = step_icp(loc, npts, rep, &clk);
    } else if (global_running(loc)) {
        stage_switch(&clk, RSM_STAGE_MAPMATCH);
        outcome = step_global(loc, npts, rep);
        global_taken = outcome == RSM_SCAN_ACCEPTED;
    } else if (loc->cfg->method == RSM_METHOD_MAP) {
        outcome = step_map(loc, npts, odometry_moved,
                           (float)(scan->stamp_us - loc->last_stamp_us) * 1.0e-6f, rep, &clk, &contradicted, &carried);
    } else {
        outcome = step_rsm(loc, npts, rep, &clk);
    }
    /* A robot standing still sees the same walls again: nothing new. On a
     * frozen map the map is the frame, drift cannot build up in it, and a
     * pull towards walls a map holds a little turned (an imported map's
     * cells) would only argue with every match. */
    if (loc->cfg->method == RSM_METHOD_MAP && !loc->cfg->map_frozen &&
        (outcome == RSM_SCAN_FIRST || (outcome == RSM_SCAN_ACCEPTED &&
        odometry_moved && !contradicted && !rep->recovered && rep->fit_ratio >= loc->cfg->track_min_fit))) {
        wall_heading(loc, npts);
    }
    if (calibrating(loc)) {
        calibrate(loc, outcome, prior_var, rep->recovered || rep->odometry != RSM_ODOMETRY_TRUSTED);
    }
    stage_switch(&clk, RSM_STAGE_MAP);
    est = loc->ekf.x;
    if (loc->cfg->method == RSM_METHOD_MAP) {
        /* Odometry is counted from the last scan that trusted it: through
         * a stall (it stands still), past a step the scan refuted, past one
         * the match had to correct by more than a doubt, and past one no
         * match checked (a scan refused or unusable). */
        const int agreed = outcome == RSM_SCAN_ACCEPTED && rep->odometry == RSM_ODOMETRY_TRUSTED &&
                           odometry_moved && !beyond_doubt(loc->cfg, &pred, &est);
        if (outcome == RSM_SCAN_FIRST || agreed || global_taken || rep->odometry == RSM_ODOMETRY_CAUGHT_UP ||
            rep->odometry == RSM_ODOMETRY_RECOUNTED) {
            static const rsm_pose_t none = {0.0f, 0.0f, 0.0f};
            loc->state.persistent.trusted = est;
            loc->state.persistent.since = none;
        } else {
            loc->state.persistent.held = !odometry_moved ? RSM_ODOMETRY_CAUGHT_UP
                                         : rep->odometry == RSM_ODOMETRY_REFUTED ? RSM_ODOMETRY_REFUTED
                                                                                 : RSM_ODOMETRY_RECOUNTED;
        }
        /* The robot's step: the estimate's, but odometry's where a search
         * jumped (a jump is no speed). */
        if (outcome == RSM_SCAN_FIRST || global_taken || outcome == RSM_SCAN_SEARCHING) {
            static const rsm_pose_t none = {0.0f, 0.0f, 0.0f};
            loc->state.persistent.last_step = none;
        } else {
            loc->state.persistent.last_step =
                rsm_pose_between(&loc->state.persistent.anchor, rep->recovered ? &pred : &est);
        }
        loc->state.persistent.anchor = est;
    }
    if (npts >= loc->cfg->min_points) {
        const int fused = outcome == RSM_SCAN_ACCEPTED || outcome == RSM_SCAN_FIRST || outcome == RSM_SCAN_ODOMETRY;
        switch (loc->cfg->method) {
        case RSM_METHOD_MAP:
            /* A scan that found too little map to match (new ground, or the
             * map there was evicted) is written at the prediction, or the
             * map could never grow back; one that was refused, or whose beams
             * pass through the map's walls (conflict_max), is not. */
            if ((fused || outcome == RSM_SCAN_LOW_SUPPORT) && !contradicted && !loc->cfg->map_frozen &&
                !recovering(loc)) {
                contradicted = write_tmap(loc, &est, npts, outcome == RSM_SCAN_FIRST,
                                          outcome == RSM_SCAN_LOW_SUPPORT, rep);
            }
            break;
        case RSM_METHOD_PAPER:
            if (fused || loc->cfg->map_on_reject) {
                (void)rsm_map_recenter(&loc->state.paper.map, est.x, est.y);
                to_world(loc, &est, npts);
                (void)rsm_map_add_points(&loc->state.paper.map, loc->frame.world, npts);
            }
            break;
        case RSM_METHOD_ICP:
            if (fused || loc->cfg->map_on_reject) {
                to_world(loc, &est, npts);
                (void)rsm_icp_set_reference(&loc->state.icp, loc->frame.world, npts);
            }
            break;
        default:
            break;
        }
        loc->have_scan = 1u;
    }
    if (loc->cfg->method == RSM_METHOD_MAP) {
        /* The first scan matched nothing, so it has the time to write all
         * of itself, and the second has a whole map to match. */
        (void)rsm_tmap_write_run(&loc->state.persistent.map, loc->frame.world,
                                 outcome == RSM_SCAN_FIRST ? 0u : loc->cfg->tmap.write_cells);
    }
    if (contradicted) {
        loc->counters.contradicted++;
    }
    rep->track = track_state(loc, outcome, rep, contradicted || carried);
    if (global_running(loc)) {
        /* Searching, the estimate is unknown whatever the scans did. */
        rep->track = RSM_TRACK_LOST;
    } else if (rep->track == RSM_TRACK_LOST && loc->cfg->method == RSM_METHOD_MAP && loc->cfg->global_when_lost &&
               rsm_global_check(&loc->state.persistent.map, search_bytes(loc)) == RSM_OK) {
        /* Near where it was lost first (the recovery's reach), the window
         * doubling with each search that proves nothing. */
        begin_global(loc, loc->cfg->recover_m > 0.0f && !carried ? loc->cfg->recover_m : 0.0f);
    }
    loc->counters.track[rep->track]++;
    loc->last_stamp_us = scan->stamp_us;
    loc->counters.outcome[outcome]++;
    rep->outcome = outcome;
    rep->pose = est;
    memcpy(rep->cov, loc->ekf.p, sizeof rep->cov);
    stage_end(&clk);
    /* The filter's own kept (unsure() weighs what odometry added to it),
     * the caller's with the floors. */
    loc->last = *rep;
    reported_cov(loc, rep->cov);
    return RSM_OK;
}
