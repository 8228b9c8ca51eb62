/* rsm-nav: runs the rsm localizer (or the ICP baseline, or odometry alone)
 * over a CARMEN log, a capture file, or live serial links, and writes the
 * trajectory, the map and a summary.
 *
 *   rsm-nav (--carmen LOG | --capture FILE | --robot DEV (--lms DEV | --lidar ld06|rplidar DEV))
 *           [--method rsm|icp|odometry]
 *           --trajectory OUT.txt [--map OUT.pgm] [--laser-pose X Y THETA] [--upside-down]
 *           [--set key=value ...] [--quiet]
 */
#include <errno.h>
#include <float.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "capture.h"
#include "carmen.h"
#include "live.h"
#include "logrun.h"
#include "pgm.h"
#include "rosmap.h"
#include "devices.h"
#include "heap.h"
#include "rsm/localizer.h"
#include "rsm/mapfile.h"
#include "rsm/tilestore.h"
#include "rsm/status.h"
#include "rsm/sync.h"
#include "map/tilemap.h" /* internal (src/): tiles held per level, for the summary */


/* Every --set KEY: F float field, U unsigned or int field, E enum field
 * with its largest value. One list for the parser and the help text. */
#define NAV_SET_KEYS(F, U, E) \
    F("cell", grid.cell_m) \
    F("sigma", grid.sigma_m) \
    E("rule", grid.rule, rsm_grid_rule_t, 2.0) \
    U("min_hits", map_min_hits, uint8_t) \
    F("window", match_window_m) \
    F("search_sigmas", search_sigmas) \
    F("search_min", search_min_m) \
    F("search_max", search_max_m) \
    F("gate", gate_d2) \
    E("noise", noise, rsm_noise_model_t, 1.0) \
    F("r_min_xy", r_min_xy_m) \
    F("r_min_theta", r_min_theta_rad) \
    F("inlier_tol", ransac.inlier_tol_m) \
    F("length_tol", ransac.length_tol_m) \
    U("iterations", ransac.max_iterations, uint32_t) \
    U("min_support", ransac.min_support, uint32_t) \
    U("seed", ransac.seed, uint32_t) \
    U("k_den", harris.k_den, int32_t) \
    U("nms", harris.nms_radius, int32_t) \
    U("min_response", harris.min_response, int32_t) \
    F("max_range", limits.max_range_m) \
    F("min_range", limits.min_range_m) \
    U("icp_iterations", icp.max_iterations, uint16_t) \
    F("icp_pair_dist", icp.max_pair_dist_m) \
    F("trans_per_m", odometry.sigma_trans_per_m) \
    F("rot_per_rad", odometry.sigma_rot_per_rad) \
    F("rot_per_m", odometry.sigma_rot_per_m) \
    U("map_on_reject", map_on_reject, uint8_t) \
    U("refine", refine_iterations, uint32_t) \
    U("refine_sat", refine_saturation, uint8_t) \
    F("refine_scale", refine_noise_scale) \
    F("mount_x", laser_mount.x) \
    F("mount_y", laser_mount.y) \
    F("mount_theta", laser_mount.theta) \
    U("upside_down", laser_upside_down, uint8_t) \
    F("map_cell", tmap.cell_m) \
    U("map_levels", tmap.levels, uint8_t) \
    U("map_hit", tmap.hit_inc, uint8_t) \
    U("map_miss", tmap.miss_dec, uint8_t) \
    U("map_loaded_hit", map_loaded_hit, uint8_t) \
    U("map_sat", tmap.saturation, uint8_t) \
    U("map_margin", tmap.clear_margin, uint8_t) \
    U("map_splat_from", tmap.splat_from, uint8_t) \
    U("map_age_shift", tmap.age_shift, uint8_t) \
    U("map_unconfirmed_shift", tmap.unconfirmed_shift, uint8_t) \
    U("map_wall_level", tmap.wall_level, uint8_t) \
    U("map_wall_value", tmap.wall_value, uint8_t) \
    U("map_wall_echo", tmap.wall_echo, uint8_t) \
    U("map_write_cells", tmap.write_cells, uint16_t) \
    U("mm_iterations", mapmatch.iterations, uint8_t) \
    F("mm_sigma", mapmatch.sigma) \
    F("mm_search", mapmatch.search_rad) \
    U("mm_fan", mapmatch.fan, uint8_t) \
    F("mm_gate", mapmatch.gate_d2) \
    F("mm_basin", mapmatch.basin) \
    F("mm_unpin_lo", mapmatch.unpin_lo) \
    F("mm_unpin_hi", mapmatch.unpin_hi) \
    F("recover_ratio", recover_ratio) \
    F("recover_m", recover_m) \
    F("recover_rad", recover_rad) \
    F("recover_margin", recover_margin) \
    U("recover_budget", recover_budget, uint32_t) \
    F("refute_margin", refute_margin) \
    F("track_min_fit", track_min_fit) \
    F("conflict_max", conflict_max) \
    U("lost_scans", lost_scans, uint16_t) \
    U("refuse_poor", refuse_poor, uint8_t) \
    U("global_budget", global_budget, uint32_t) \
    F("global_min_share", global_min_share) \
    F("global_min_fit", global_min_fit) \
    F("global_crowded_fit", global_crowded_fit) \
    U("global_when_lost", global_when_lost, uint8_t) \
    F("doubt_m", doubt_m) \
    F("doubt_rad", doubt_rad) \
    F("wall_sigma_rad", wall_sigma_rad) \
    F("wall_window_rad", wall_window_rad) \
    F("cov_floor_m", cov_floor_m) \
    F("cov_floor_rad", cov_floor_rad) \
    F("mm_search_step", mapmatch.search_step_rad) \
    F("mm_min_step", mapmatch.min_step_m) \
    F("mm_min_rad", mapmatch.min_step_rad) \
    F("map_update_m", map_update_m) \
    F("map_update_rad", map_update_rad) \
    F("iso_tol", isolation.tol_m) \
    F("iso_slope", isolation.slope) \
    U("iso_window", isolation.window, uint8_t) \
    U("iso_agree", isolation.agree, uint8_t) \
    U("occl_window", occlusion.window, uint8_t) \
    F("occl_span", occlusion.span_m) \
    F("occl_tol", occlusion.tol_m) \
    F("occl_slope", occlusion.slope) \
    F("occl_margin", occlusion.margin_m) \
    F("occl_margin_rel", occlusion.margin_rel) \
    F("odo_cal_memory", odometry_cal.memory) \
    F("odo_cal_prior", odometry_cal.prior) \
    F("odo_cal_max_turn", odometry_cal.max_turn) \
    F("odo_cal_max_drift", odometry_cal.max_drift) \
    F("odo_cal_gate", odometry_cal.gate_rad) \
    F("odo_cal_max_scale", odometry_cal.max_scale) \
    F("odo_cal_gate_m", odometry_cal.gate_m) \
    F("odo_cal_scale_prior", odometry_cal.scale_prior_m)

/* Prints the --set keys, comma separated, wrapped before 80 columns. */
static void print_set_keys(FILE *f)
{
#define NAME_F(name, field) name,
#define NAME_U(name, field, type) name,
#define NAME_E(name, field, type, maxv) name,
    static const char *const names[] = {NAV_SET_KEYS(NAME_F, NAME_U, NAME_E)};
#undef NAME_F
#undef NAME_U
#undef NAME_E
    const size_t n = sizeof names / sizeof names[0];
    size_t col = 0;
    size_t k;
    for (k = 0; k < n; ++k) {
        const size_t w = strlen(names[k]);
        if (k > 0u) {
            const int wrap = col + 2u + w > 79u;
            fputs(wrap ? ",\n" : ", ", f);
            col = wrap ? 0u : col + 2u;
        }
        fputs(names[k], f);
        col += w;
    }
    fputs(".\n", f);
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: rsm-nav SOURCE [--method rsm|icp|odometry] --trajectory OUT.txt [--map OUT.pgm]\n"
            "               [--laser-pose X Y THETA] [--upside-down] [--set KEY=VALUE]... [--quiet]\n"
            "SOURCE is one of:\n"
            "  --carmen LOG [--fov179] [--odom-lines]   a CARMEN log, plain or gzip\n"
            "                            (FLASER/ROBOTLASER1 scans; odometry from the pose fields\n"
            "                            of the laser lines, and with --odom-lines each ODOM line\n"
            "                            between them a step too; a pipe is read once: no mount\n"
            "                            looked up in it)\n"
            "  --capture FILE            a capture of the robot (ARIA) and laser (LMS, or an\n"
            "                            rsm-convert --lidar ld06|rplidar stream) links\n"
            "  --robot DEV --lms DEV     live serial links (devices or pseudo-terminals), with\n"
            "     [--robot-baud N] [--lms-baud N] [--listen] [--seconds S] [--idle-exit S]\n"
            "     [--lost-exit S]       --listen sends nothing and decodes what arrives (replays);\n"
            "                            --idle-exit S stops S s after the last byte on any link,\n"
            "                            --lost-exit S once a device lost S s ago is not back\n"
            "  --robot DEV --lidar ld06|rplidar DEV   the same with a spinning lidar instead of\n"
            "                            the LMS (--lms-baud sets its rate); its turns become scans,\n"
            "                            de-skewed with the encoder packets' odometry\n"
            "  --lidar-keep N            lidar: keep one point in N (an LD06's 450 a turn need 2)\n"
            "  --no-deskew               lidar: place every point of a turn at the turn's pose\n"
            "  --ticks-per-m N --wheel-base M   odometry geometry for encoder packets\n"
            "                            (default: the capture's, else the P3-DX defaults)\n"
            "  --events FILE             write every decoded input (E left right / S count hash;\n"
            "                            live, each line as it comes)\n"
            "  --summary-json FILE       write the summary as JSON too (scans, outcomes, times, map)\n"
            "  --scan-log FILE           one line per scan: stamp, outcome, tracking state,\n"
            "                            what odometry's step was judged, 1 if a search placed it,\n"
            "                            the fit over recent scans', the pose's covariance\n"
            "                            (xx xy xt yy yt tt: m^2, m rad, rad^2)\n"
            "  --save-map FILE           save the persistent map at the end (docs/mapfile.md)\n"
            "  --load-map FILE|MAP.yaml  start in a saved map, or a ROS map_server map\n"
            "  --freeze-map              localization mode: the map is read, never written\n"
            "  --tile-store N            keep up to N tiles the map's pool lets go in memory and\n"
            "                            take them back when the robot returns, so that a building\n"
            "                            larger than the pool is kept whole (saved with --save-map;\n"
            "                            40 bytes a tile; 0: none, the default)\n"
            "  --search-memory BYTES     memory lent to the global search's grids: with more it\n"
            "                            reads fewer map cells to the same pose (default %lu;\n"
            "                            0: none, the %lu bytes it shares with a map write)\n"
            "  --global                  no start pose: search the loaded map for the robot; no\n"
            "                            trajectory line until a pose is proven\n"
            "  --global-near R           the same within R m of the start pose (--initial-pose),\n"
            "                            the window doubling after each search that proves nothing\n"
            "  --skip-seconds S          --carmen: start S seconds into the log, as if the robot\n"
            "                            were switched on there\n"
            "  --scans N                 --carmen: stop after N scans; live: once the laser\n"
            "                            gave N scans and the robot connected\n",
            (unsigned long)RSM_GLOBAL_LEND_BYTES, (unsigned long)RSM_GLOBAL_GRID_BYTES);
    fprintf(f,
            "  --tum FILE                write the trajectory in TUM format too\n"
            "                            (timestamp x y z qx qy qz qw; what evo reads)\n"
            "  --initial-pose X Y THETA  start pose (default: the log's first odometry pose,\n"
            "                            the capture's robot.initial_pose, else zero)\n"
            "  --laser-pose X Y THETA    the laser's pose on the robot (m, m, rad; x forward,\n"
            "                            y left, theta CCW). Default: with --carmen the laser pose\n"
            "                            of the log's first ROBOTLASER1 line (or of a FLASER line\n"
            "                            whose laser pose differs from its odometry), else zero.\n"
            "                            Given, it overrides the log (as --set mount_x= etc. do)\n"
            "  --upside-down             the laser is mounted upside down (beam angles mirrored;\n"
            "                            no log says so)\n"
            "Writes one line per scan: timestamp x y theta (s, m, m, rad).\n"
            "KEY is one of the names below (rule: 0 inside, 1 touch, 2 nearest; noise: 0 residual,\n"
            "1 fixed; refine: iterations, 0 = off; mount_* and upside_down as --laser-pose and\n"
            "--upside-down):\n");
    print_set_keys(f);
}

/* The largest value an integer field of this size holds (enums: int). */
static double set_option_max(size_t size, int is_unsigned)
{
    const double bits = (double)size * 8.0 - (is_unsigned ? 0.0 : 1.0);
    return pow(2.0, bits) - 1.0;
}

/* Sets one KEY=VALUE. Returns 0, -1 (not KEY=number), -2 (an integer
 * field and VALUE is not a whole number from 0 to *top_out) or -3 (no such
 * KEY). */
static int set_option(rsm_localizer_config_t *c, const char *kv, double *top_out)
{
    const char *eq = strchr(kv, '=');
    char key[64];
    char *end;
    double v;
    size_t len;
    if (eq == NULL || (len = (size_t)(eq - kv)) == 0 || len >= sizeof key) {
        return -1;
    }
    memcpy(key, kv, len);
    key[len] = '\0';
    errno = 0;
    v = strtod(eq + 1, &end);
    if (*end != '\0' || end == eq + 1 || errno != 0 || !isfinite(v)) {
        return -1;
    }
/* Integers must fit their field: a silent conversion would turn 257 into 1
 * and 1e12 into undefined behaviour. */
/* A float field takes only what a float holds: 1e39 would become infinity. */
#define F(name, field) \
    if (strcmp(key, name) == 0) { \
        if (!(fabs(v) <= (double)FLT_MAX)) { \
            return -4; \
        } \
        c->field = (float)v; \
        return 0; \
    }
#define U(name, field, type) E(name, field, type, set_option_max(sizeof(c->field), (type)-1 > 0))
#define E(name, field, type, maxv) \
    if (strcmp(key, name) == 0) { \
        const double top = (maxv); \
        if (!(v >= 0.0 && v <= top) || v != floor(v)) { \
            *top_out = top; \
            return -2; \
        } \
        c->field = (type)v; \
        return 0; \
    }
    NAV_SET_KEYS(F, U, E)
#undef F
#undef U
#undef E
    return -3;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* The per-scan time bins: from NAV_TIME_FLOOR_S up, each NAV_TIME_STEP times
 * the one before; 2400 of them reach past 2 000 s. */
#define NAV_TIME_BINS 2400u
#define NAV_TIME_FLOOR_S 1e-7
#define NAV_TIME_STEP 1.01

/* The bin of a wall time t (s): 0 for up to 0.1 us, then 1 % wider each. */
static size_t time_bin(double t)
{
    double b;
    if (!(t > NAV_TIME_FLOOR_S)) {
        return 0u;
    }
    b = floor(log(t / NAV_TIME_FLOOR_S) / log(NAV_TIME_STEP)) + 1.0;
    return b < (double)(NAV_TIME_BINS - 1) ? (size_t)b : NAV_TIME_BINS - 1u;
}

/* The middle of bin b (geometric): within half a per cent of any time in it. */
static double bin_time(size_t b)
{
    return b == 0u ? 0.0 : NAV_TIME_FLOOR_S * pow(NAV_TIME_STEP, (double)b - 0.5);
}

/* Everything one run accumulates, whatever the source. */
typedef struct nav {
    rsm_localizer_t loc;
    rsm_localizer_config_t cfg;
    int initialised;
    int quiet;
    FILE *traj;
    const char *map_path;
    hitmap_t hits;         /* --map: hit counts per picture cell */
    /* Per-scan wall times, counted in bins 1 % wide from 0.1 us up (fixed
     * memory however long the run: an array of every time grew by 8 bytes
     * and more a scan, about 95 MB a day at 75 Hz). */
    uint64_t time_bins[NAV_TIME_BINS];
    size_t ntimes;
    uint64_t poses;        /* trajectory lines written */
    int live;              /* a live run: outputs flushed at every pose */
    stamp_repair_t repair; /* scan stamps as the localizer gets them */
    double t_start;
    /* Capture mode: the drivers' clock is the records' stamps plus this
     * (modulo 2^64), so that it carries on across a step of the capture's
     * clock; the trajectory keeps the capture's own stamps. */
    uint64_t cap_base_us;
    /* Capture mode: original stamps of scans whose stamp the converter clamped. */
    uint64_t *restore_idx;
    int64_t *restore_us;   /* signed: a log's stamp may be negative */
    size_t nrestore;
    size_t restore_next;   /* the table is in scan order: a cursor, not a search */
    uint64_t scan_index;
    uint64_t encoders;
    FILE *events;          /* --events: decoded inputs, one line each, in processing order */
    FILE *tum;             /* --tum: the trajectory again, as TUM lines (what evo reads) */
    FILE *scan_log;        /* --scan-log: what each scan did (the bench counts false recoveries) */
    int ticks_from_flag;   /* --ticks-per-m given: the robot's calibration is not taken */
    unsigned calibrations; /* robot calibrations taken (live mode) */
    int have_x0;           /* --initial-pose given: overrides any other start */
    rsm_pose_t x0;
    /* Far from the origin the localizer runs in a frame shifted by this
     * (metres, added back to every output): floats resolve 3 cm at 5e5 m. */
    double off_x;
    double off_y;
    /* Capture and live modes: odometry and scans aligned in time (sync.h). */
    rsm_sync_config_t sync_cfg;
    rsm_sync_t sync;
    double call_t0;        /* when the sync call that is fusing scans began */
    double file_s[4];      /* trajectory stamps of scans waiting in the aligner, FIFO */
    unsigned file_head;
    unsigned file_count;
    /* The laser's mount (cfg.laser_mount, cfg.laser_upside_down) and where it came from. */
    int mount_flag;        /* --laser-pose or --set mount_*: overrides the log */
    const char *mount_source;   /* "flag", "log ROBOTLASER1", "log FLASER" or "default zero" */
    char mount_note[224];  /* the log's mount when a flag overrode it, or why it was not used */
    uint64_t mount_disagree;    /* later log laser poses off the first by more than the tolerance */
    int no_deskew;         /* --no-deskew: a lidar's turns are not de-skewed */
    /* Known maps (docs/mapfile.md, docs/globalsearch.md). */
    const char *save_map;  /* --save-map: the persistent map at the end */
    const char *load_map;  /* --load-map: the map to start in */
    int global;            /* --global: no start pose: search the loaded map */
    float global_near_m;   /* --global-near: only within this of the start pose at first (0: all) */
    double skip_s;         /* --skip-seconds: scans before the log's first stamp + this are left out */
    uint64_t max_scans;    /* --scans: stop after this many scans (0: the whole log) */
    int have_first_stamp;
    double first_stamp_s;
    uint64_t first_trusted;    /* scan (1-based) of the first pose written after --global; 0: none */
    double first_trusted_s;
    uint32_t max_search_work;  /* the most cells and blocks the global search read in one scan */
    rsm_mapfile_info_t loaded; /* what --load-map read */
    /* --tile-store: the tiles the map's pool lets go, kept in memory. */
    uint32_t store_tiles;
    rsm_tile_t *store_tile;
    uint32_t *store_index;
    rsm_tilestore_mem_t store_mem;
    rsm_tile_store_t store;
    /* --search-memory: lent to the global search's grids (0: none). */
    unsigned long search_bytes;
    uint8_t *search_mem;
} nav_t;

static void on_fused(void *ctx, const rsm_scan_t *scan, int status, const rsm_localizer_report_t *rep);

/* The map file callbacks (rsm/mapfile.h) on a stdio stream. */
static int file_write(void *ctx, uint32_t offset, const uint8_t *buf, size_t len)
{
    FILE *f = (FILE *)ctx;
    return fseek(f, (long)offset, SEEK_SET) == 0 && fwrite(buf, 1, len, f) == len ? 0 : -1;
}

static int file_read(void *ctx, uint32_t offset, uint8_t *buf, size_t len)
{
    FILE *f = (FILE *)ctx;
    return fseek(f, (long)offset, SEEK_SET) == 0 && fread(buf, 1, len, f) == len ? 0 : -1;
}

static int ends_with(const char *s, const char *tail)
{
    const size_t n = strlen(s);
    const size_t t = strlen(tail);
    return n >= t && strcmp(s + n - t, tail) == 0;
}

/* --load-map: an rsm map (rsm-nav --save-map), or a ROS map's YAML. */
static int nav_load_map(nav_t *nav)
{
    FILE *f;
    int rc;
    if (ends_with(nav->load_map, ".yaml") || ends_with(nav->load_map, ".yml")) {
        rsm_import_report_t rep;
        char err[256];
        const int r = rsm_rosmap_load(nav->load_map, &nav->loc, &rep, err, sizeof err);
        if (r < 0) {
            fprintf(stderr, "rsm-nav: cannot load the map %s: %s\n", nav->load_map, err);
            return -1;
        }
        if (r > 0) {
            fprintf(stderr, "rsm-nav: the map %s is loaded only in part: %s\n", nav->load_map, err);
        }
        nav->loaded.bytes = 0u;
        nav->loaded.tiles = nav->loc.state.persistent.map.used;
        return 0;
    }
    f = fopen(nav->load_map, "rb");
    if (f == NULL) {
        fprintf(stderr, "rsm-nav: cannot open the map %s: %s\n", nav->load_map, strerror(errno));
        return -1;
    }
    rc = rsm_localizer_load_map(&nav->loc, file_read, f, &nav->loaded);
    (void)fclose(f);
    if (rc != RSM_OK) {
        fprintf(stderr, "rsm-nav: the map %s is refused: %s\n", nav->load_map,
                rc == RSM_ERR_IO ? "it ends early or cannot be read (truncated)" : rsm_strerror(rc));
        return -1;
    }
    return 0;
}

/* --save-map at the end of a run. */
static int nav_save_map(nav_t *nav)
{
    char tmp[4096];
    rsm_mapfile_info_t info;
    int rc;
    FILE *f;
    /* Written beside and renamed over: a failed save leaves the old map,
     * not half a new one. */
    if (snprintf(tmp, sizeof tmp, "%s.part", nav->save_map) >= (int)sizeof tmp) {
        fprintf(stderr, "rsm-nav: the map path %s is too long\n", nav->save_map);
        return -1;
    }
    f = fopen(tmp, "wb");
    if (f == NULL) {
        fprintf(stderr, "rsm-nav: cannot write the map %s: %s\n", tmp, strerror(errno));
        return -1;
    }
    rc = rsm_localizer_save_map(&nav->loc, file_write, f, &info);
    if (fclose(f) != 0 && rc == RSM_OK) {
        rc = RSM_ERR_IO;
    }
    if (rc == RSM_OK && rename(tmp, nav->save_map) != 0) {
        fprintf(stderr, "rsm-nav: cannot rename %s to %s: %s\n", tmp, nav->save_map, strerror(errno));
        (void)remove(tmp);
        return -1;
    }
    if (rc != RSM_OK) {
        (void)remove(tmp);
        fprintf(stderr, "rsm-nav: cannot save the map %s: %s\n", nav->save_map, rsm_strerror(rc));
        return -1;
    }
    printf("  map saved       %s: %u bytes, %u tiles\n", nav->save_map, (unsigned)info.bytes, (unsigned)info.tiles);
    return 0;
}

/* Beyond this distance of the start from the origin, the localizer works in
 * a frame centred on the start (see off_x). */
#define NAV_LOCAL_FRAME_M 1000.0

/* Starts the localizer once, at x0 (x, y, theta; NULL: zero) unless
 * --initial-pose gave the start; where is the start's source, for messages. */
static int nav_start(nav_t *nav, const double *x0, const char *where)
{
    double x = 0.0;
    double y = 0.0;
    double th = 0.0;
    rsm_pose_t start;
    if (nav->initialised) {
        return 0;
    }
    if (nav->have_x0) {
        x = nav->x0.x;
        y = nav->x0.y;
        th = nav->x0.theta;
        where = "--initial-pose";
    } else if (x0 != NULL) {
        x = x0[0];
        y = x0[1];
        th = x0[2];
    }
    if (!isfinite(x) || !isfinite(y) || !isfinite(th)) {
        fprintf(stderr, "rsm-nav: the start pose from %s is not finite (%g %g %g)\n", where, x, y, th);
        return -1;
    }
    /* A loaded map is in its own frame: poses are its, not shifted. */
    if (nav->load_map == NULL && (fabs(x) > NAV_LOCAL_FRAME_M || fabs(y) > NAV_LOCAL_FRAME_M)) {
        nav->off_x = x;
        nav->off_y = y;
    }
    start.x = (float)(x - nav->off_x);
    start.y = (float)(y - nav->off_y);
    start.theta = rsm_wrap_angle((float)th);
    if (rsm_localizer_init(&nav->loc, &nav->cfg, &start, NULL) != RSM_OK) {
        const char *field = NULL;
        if (rsm_localizer_config_check(&nav->cfg, &field) != RSM_OK) {
            fprintf(stderr, "rsm-nav: invalid configuration: the localizer refuses its field %s (a --set value,"
                            " the laser pose or the odometry geometry is out of range)\n", field);
        } else {
            fprintf(stderr, "rsm-nav: invalid configuration (the start pose is out of range)\n");
        }
        return -1;
    }
    if (nav->store_tiles > 0u) {
        const uint32_t ilog = rsm_tilestore_mem_index_log2(nav->store_tiles);
        nav->store_tile = (rsm_tile_t *)nav_calloc(nav->store_tiles, sizeof *nav->store_tile);
        nav->store_index = (uint32_t *)nav_calloc((size_t)1u << ilog, sizeof *nav->store_index);
        if (nav->store_tile == NULL || nav->store_index == NULL ||
            rsm_tilestore_mem_init(&nav->store_mem, nav->store_tile, nav->store_tiles, nav->store_index, ilog,
                                   &nav->store) != RSM_OK ||
            rsm_localizer_set_store(&nav->loc, &nav->store) != RSM_OK) {
            fprintf(stderr, "rsm-nav: cannot set up a tile store of %u tiles\n", (unsigned)nav->store_tiles);
            return -1;
        }
    }
    if (nav->cfg.method == RSM_METHOD_MAP && nav->search_bytes > 0u) {
        /* Lent before a load, whose grids are then built into it. */
        nav->search_mem = (uint8_t *)nav_calloc(nav->search_bytes, 1u);
        if (nav->search_mem == NULL ||
            rsm_localizer_set_search_memory(&nav->loc, nav->search_mem, nav->search_bytes) != RSM_OK) {
            fprintf(stderr, "rsm-nav: cannot lend the global search %lu bytes\n", nav->search_bytes);
            return -1;
        }
    }
    if (nav->load_map != NULL && nav_load_map(nav) != 0) {
        return -1;
    }
    if (nav->global) {
        const int g = rsm_localizer_global_near(&nav->loc, nav->global_near_m);
        if (g != RSM_OK) {
            fprintf(stderr, "rsm-nav: cannot start a global search: %s\n", rsm_strerror(g));
            return -1;
        }
    }
    if (rsm_sync_init(&nav->sync, &nav->loc, &nav->sync_cfg, on_fused, nav) != RSM_OK) {
        fprintf(stderr, "rsm-nav: invalid alignment settings\n");
        return -1;
    }
    nav->initialised = 1;
    return 0;
}

/* This scan's usable readings, as the localizer saw them, placed at its
 * estimate, into the --map picture. */
static void nav_map_points(nav_t *nav, const rsm_localizer_report_t *rep)
{
    static rsm_point_t pts[RSM_MAX_BEAMS];
    size_t k;
    const size_t got = rsm_localizer_scan_points(&nav->loc, pts, RSM_MAX_BEAMS);
    const size_t n = got <= RSM_MAX_BEAMS ? got : RSM_MAX_BEAMS;
    for (k = 0; k < n; ++k) {
        pts[k] = rsm_pose_apply(&rep->pose, &pts[k]);
    }
    if (hitmap_add(&nav->hits, pts, n) != 0) {
        fprintf(stderr, "rsm-nav: out of memory for the map picture\n");
        exit(1);
    }
}

/* Records one fused scan: time taken, trajectory line, map points. */
static void nav_result(nav_t *nav, int rc, const rsm_localizer_report_t *rep, double elapsed_s,
                       double file_stamp_s)
{
    nav->time_bins[time_bin(elapsed_s)]++;
    nav->ntimes++;
    if (nav->scan_log != NULL) {
        const float *c = rep->cov;
        fprintf(nav->scan_log, "%.6f %s %s %s %u %.4f %.4e %.4e %.4e %.4e %.4e %.4e\n", file_stamp_s,
                rc == RSM_OK || rc == RSM_ERR_ORDER ? rsm_outcome_name(rep->outcome) : "error",
                rsm_track_name(rep->track),
                rsm_odometry_verdict_name(rep->odometry), (unsigned)rep->recovered, (double)rep->fit_ratio,
                (double)c[0], (double)c[1], (double)c[2], (double)c[4], (double)c[5], (double)c[8]);
    }
    if (rc != RSM_OK) {
        fprintf(stderr, "rsm-nav: scan at %.6f: %s\n", file_stamp_s, rsm_strerror(rc));
        return;
    }
    if (rep->search_work > nav->max_search_work) {
        nav->max_search_work = rep->search_work;
    }
    if (rsm_localizer_searching(&nav->loc) || rep->outcome == RSM_SCAN_SEARCHING) {
        return; /* no pose is trusted yet: no trajectory line */
    }
    if (nav->global && nav->first_trusted == 0u) {
        nav->first_trusted = nav->ntimes;
        nav->first_trusted_s = file_stamp_s;
    }
    nav->poses++;
    fprintf(nav->traj, "%.6f %.6f %.6f %.6f\n", file_stamp_s, nav->off_x + (double)rep->pose.x,
            nav->off_y + (double)rep->pose.y, (double)rep->pose.theta);
    if (nav->tum != NULL) {
        /* A rotation about z by theta: the quaternion (0, 0, sin theta/2, cos theta/2). */
        const double half = 0.5 * (double)rep->pose.theta;
        fprintf(nav->tum, "%.6f %.6f %.6f 0 0 0 %.9f %.9f\n", file_stamp_s, nav->off_x + (double)rep->pose.x,
                nav->off_y + (double)rep->pose.y, sin(half), cos(half));
    }
    if (nav->map_path != NULL) {
        nav_map_points(nav, rep);
    }
    if (nav->live) {
        /* A live run may end by power loss or kill -9: each pose on disk
         * (the kernel's, at least) as it comes. */
        (void)fflush(nav->traj);
        if (nav->tum != NULL) {
            (void)fflush(nav->tum);
        }
        if (nav->scan_log != NULL) {
            (void)fflush(nav->scan_log);
        }
    }
    if (!nav->quiet && nav->ntimes % 1000 == 0) {
        fprintf(stderr, "rsm-nav: %zu scans, %.1f s\n", nav->ntimes, now_s() - nav->t_start);
    }
}

/* The aligner fused a scan (capture and live modes). */
static void on_fused(void *ctx, const rsm_scan_t *scan, int status, const rsm_localizer_report_t *rep)
{
    nav_t *nav = (nav_t *)ctx;
    const double now = now_s();
    double file_s = (double)scan->stamp_us * 1e-6;
    if (nav->file_count > 0u) {
        file_s = nav->file_s[nav->file_head];
        nav->file_head = (nav->file_head + 1u) % 4u;
        nav->file_count--;
    }
    nav_result(nav, status, rep, now - nav->call_t0, file_s);
    nav->call_t0 = now;
}

/* Stream sink callbacks (capture and live modes). */
static void sink_encoder(void *ctx, const rsm_odometry_sample_t *sample, int restart)
{
    nav_t *nav = (nav_t *)ctx;
    if (nav_start(nav, NULL, "the default") != 0) {
        return;
    }
    if (restart) {
        (void)rsm_sync_encoder_restart(&nav->sync); /* no step across a new connection */
    }
    nav->encoders++;
    if (nav->events != NULL) {
        /* Printed as the packet's signed 32-bit values. */
        fprintf(nav->events, "E %ld %ld\n", (long)rsm_odometry_count_delta(sample->left, 0u, 32u),
                (long)rsm_odometry_count_delta(sample->right, 0u, 32u));
        if (nav->live) {
            (void)fflush(nav->events); /* as the poses: on disk as it comes */
        }
    }
    nav->call_t0 = now_s();
    (void)rsm_sync_encoder(&nav->sync, sample);
}

/* The robot reported its TicksMM: the odometry takes it from the next
 * encoder sample on, unless --ticks-per-m gave the geometry. 1 if taken. */
static int sink_calibration(void *ctx, float ticks_per_m)
{
    nav_t *nav = (nav_t *)ctx;
    rsm_odometry_config_t odo;
    if (nav->ticks_from_flag || nav_start(nav, NULL, "the default") != 0) {
        return 0;
    }
    odo = nav->loc.odo.cfg;
    odo.ticks_per_m_left = ticks_per_m;
    odo.ticks_per_m_right = ticks_per_m;
    if (rsm_localizer_set_odometry(&nav->loc, &odo) != RSM_OK) {
        fprintf(stderr, "rsm-nav: the robot's calibration (%.0f ticks/m) refused; odometry unchanged\n",
                (double)ticks_per_m);
        return 0;
    }
    nav->calibrations++;
    if (!nav->quiet) {
        fprintf(stderr, "rsm-nav: odometry from the robot: %.0f ticks/m, wheel base %.3f m\n",
                (double)ticks_per_m, (double)odo.wheel_base_m);
    }
    return 1;
}

static void sink_tick(void *ctx, uint64_t now_us)
{
    nav_t *nav = (nav_t *)ctx;
    if (nav->initialised) {
        nav->call_t0 = now_s();
        (void)rsm_sync_poll(&nav->sync, now_us);
    }
}

static void sink_scan(void *ctx, const rsm_scan_t *scan)
{
    static rsm_scan_t copy;
    nav_t *nav = (nav_t *)ctx;
    const uint64_t stamp_us = scan->stamp_us;
    double file_s = (double)(uint64_t)(stamp_us - nav->cap_base_us) * 1e-6;
    size_t k;
    while (nav->restore_next < nav->nrestore && nav->restore_idx[nav->restore_next] < nav->scan_index) {
        nav->restore_next++;
    }
    if (nav->restore_next < nav->nrestore && nav->restore_idx[nav->restore_next] == nav->scan_index) {
        file_s = (double)nav->restore_us[nav->restore_next] * 1e-6;
    }
    nav->scan_index++;
    if (nav->events != NULL) {
        /* A fingerprint of the readings: any lost or changed byte shows. */
        uint32_t h = 2166136261u;
        for (k = 0; k < scan->count; ++k) {
            const uint32_t mm = (uint32_t)lroundf(scan->range_m[k] * 1000.0f);
            h = (h ^ mm) * 16777619u;
        }
        fprintf(nav->events, "S %zu %08lx\n", scan->count, (unsigned long)h);
        if (nav->live) {
            (void)fflush(nav->events);
        }
    }
    if (nav_start(nav, NULL, "the default") != 0) {
        return;
    }
    copy = *scan;
    copy.stamp_us = stamp_repair(&nav->repair, stamp_us);
    /* At most two scans are ever inside the aligner (one waiting, one new). */
    nav->file_s[(nav->file_head + nav->file_count) % 4u] = file_s;
    nav->file_count++;
    nav->call_t0 = now_s();
    if (rsm_sync_scan(&nav->sync, &copy) != RSM_OK) {
        nav->file_count--; /* refused: never fused */
    }
}

/* A laser pose in a log farther than this from the robot's pose is not a
 * mount (the two triples are then in different frames). */
#define NAV_MOUNT_MAX_M 10.0f
/* Later laser poses within this of the first are the same mount (the log
 * writes 1 um / 1 urad). */
#define NAV_MOUNT_TOL_M 0.001f
#define NAV_MOUNT_TOL_RAD 0.001f

/* The mount from the log's first scan record that carries a laser pose
 * (looked up before the run: the localizer keeps its configuration), unless
 * a flag gave one. */
static void carmen_mount(nav_t *nav, const char *path, int fov179, rsm_pose_t *log_mount, int *have_log)
{
    static carmen_reader_t ahead;
    static carmen_record_t rec;
    struct stat st;
    *have_log = 0;
    nav->mount_source = nav->mount_flag ? "flag" : "default zero";
    if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
        /* A pipe (a log streamed in) can be read once: the mount is the
         * flag's or zero, and the run reads every line. */
        snprintf(nav->mount_note, sizeof nav->mount_note, "not looked up: the log is not a regular file");
        return;
    }
    ahead.fov179 = fov179;
    if (carmen_open(&ahead, path) != 0) {
        return; /* the real pass says why */
    }
    if (carmen_next_mount(&ahead, &rec) == CARMEN_SCAN) {
        const float d = sqrtf(rec.mount.x * rec.mount.x + rec.mount.y * rec.mount.y);
        const unsigned long long line = (unsigned long long)ahead.counts.lines;
        if (!(d <= NAV_MOUNT_MAX_M)) {
            snprintf(nav->mount_note, sizeof nav->mount_note,
                     "the %s laser pose on line %llu is %.1f m from the robot: not a mount, ignored", rec.type,
                     line, (double)d);
        } else {
            *have_log = 1;
            *log_mount = rec.mount;
            if (nav->mount_flag) {
                snprintf(nav->mount_note, sizeof nav->mount_note,
                         "overrides the log's %s mount x %.3f y %.3f theta %.4f, line %llu", rec.type,
                         (double)rec.mount.x, (double)rec.mount.y, (double)rec.mount.theta, line);
            } else {
                nav->cfg.laser_mount = rec.mount;
                nav->mount_source = strcmp(rec.type, "ROBOTLASER1") == 0 ? "log ROBOTLASER1" : "log FLASER";
                snprintf(nav->mount_note, sizeof nav->mount_note, "line %llu", line);
            }
        }
    }
    carmen_close(&ahead);
}

/* logrun ops for --carmen (CARMEN logs carry the odometry of each scan). */
typedef struct carmen_run {
    nav_t *nav;
    rsm_pose_t log_mount;
    int have_log_mount;
} carmen_run_t;

static int carmen_start_cb(void *ctx, const carmen_record_t *rec)
{
    carmen_run_t *cr = (carmen_run_t *)ctx;
    /* Start in the odometry frame so the trajectories are comparable. */
    return nav_start(cr->nav, rec->odom_d, "the log's first pose");
}

static int carmen_want_cb(void *ctx, const carmen_record_t *rec)
{
    nav_t *nav = ((carmen_run_t *)ctx)->nav;
    if (!(nav->skip_s > 0.0)) {
        return 1; /* every record, odd stamps too (the stamp repair judges those) */
    }
    if (!nav->have_first_stamp) {
        nav->have_first_stamp = 1;
        nav->first_stamp_s = rec->stamp_s;
    }
    return rec->stamp_s >= nav->first_stamp_s + nav->skip_s;
}

static int carmen_done_cb(void *ctx)
{
    const nav_t *nav = ((carmen_run_t *)ctx)->nav;
    return nav->max_scans > 0u && nav->ntimes >= nav->max_scans;
}

static void carmen_motion_cb(void *ctx, const rsm_motion_t *u)
{
    (void)rsm_localizer_motion(&((carmen_run_t *)ctx)->nav->loc, u);
}

static void carmen_scan_cb(void *ctx, const carmen_record_t *rec, uint64_t stamp_us)
{
    static rsm_scan_t scan;
    carmen_run_t *cr = (carmen_run_t *)ctx;
    nav_t *nav = cr->nav;
    rsm_localizer_report_t rep;
    double t0;
    int rc;
    if (cr->have_log_mount && rec->has_mount &&
        (fabsf(rec->mount.x - cr->log_mount.x) > NAV_MOUNT_TOL_M ||
         fabsf(rec->mount.y - cr->log_mount.y) > NAV_MOUNT_TOL_M ||
         fabsf(rsm_wrap_angle(rec->mount.theta - cr->log_mount.theta)) > NAV_MOUNT_TOL_RAD)) {
        nav->mount_disagree++;
    }
    logrun_scan(rec, &scan);
    scan.stamp_us = stamp_us;
    t0 = now_s();
    rc = rsm_localizer_scan(&nav->loc, &scan, &rep);
    nav_result(nav, rc, &rep, now_s() - t0, rec->stamp_s);
}

static int run_carmen(nav_t *nav, const char *path, int fov179, int odom_lines)
{
    static const logrun_ops_t ops = {carmen_start_cb, carmen_want_cb, carmen_motion_cb, carmen_scan_cb,
                                     carmen_done_cb};
    static carmen_reader_t reader;
    static carmen_record_t rec;
    carmen_run_t cr;
    int status;
    cr.nav = nav;
    cr.log_mount.x = cr.log_mount.y = cr.log_mount.theta = 0.0f;
    carmen_mount(nav, path, fov179, &cr.log_mount, &cr.have_log_mount);
    reader.fov179 = fov179;
    status = logrun_carmen(&reader, &rec, path, "rsm-nav", &nav->repair, &ops, &cr, odom_lines);
    if (status < 0) {
        return 1; /* not even opened: nothing to sum up */
    }
    if (status == 2) {
        return 2;
    }
    printf("rsm-nav summary\n");
    printf("  source          CARMEN log %s\n", path);
    printf("  lines           %llu (scans %llu, odometry %llu, comments %llu, unknown %llu, malformed %llu, too many beams %llu, too long %llu)\n",
           (unsigned long long)reader.counts.lines, (unsigned long long)reader.counts.scans,
           (unsigned long long)reader.counts.odoms, (unsigned long long)reader.counts.comments,
           (unsigned long long)reader.counts.unknown, (unsigned long long)reader.counts.malformed,
           (unsigned long long)reader.counts.too_many_beams, (unsigned long long)reader.counts.too_long);
    if (reader.counts.bad_pose != 0u) {
        printf("                  malformed with a NaN or infinite pose or stamp: %llu\n",
               (unsigned long long)reader.counts.bad_pose);
    }
    if (reader.counts.flaser_offset != 0u) {
        printf("                  FLASER lines whose laser pose differs from their odometry pose: %llu\n",
               (unsigned long long)reader.counts.flaser_offset);
    }
    return status;
}

static const char *meta(const cap_reader *r, const char *key)
{
    size_t i;
    for (i = 0; i < r->n_meta; ++i) {
        if (strcmp(r->meta_keys[i], key) == 0) {
            return r->meta_values[i];
        }
    }
    return NULL;
}

/* Reads "FLASER index original_us written_us" lines of convert.clamped. */
static void load_restore_table(nav_t *nav, const char *text)
{
    const char *p = text;
    size_t cap = 0;
    while (p != NULL && *p != '\0') {
        char kind[32];
        unsigned long long idx;
        long long orig;
        long long written;
        if (sscanf(p, "%31s %llu %lld %lld", kind, &idx, &orig, &written) == 4 && strcmp(kind, "FLASER") == 0) {
            if (nav->nrestore == cap) {
                cap = cap ? cap * 2 : 256;
                nav->restore_idx = (uint64_t *)nav_realloc(nav->restore_idx, cap * sizeof *nav->restore_idx);
                nav->restore_us = (int64_t *)nav_realloc(nav->restore_us, cap * sizeof *nav->restore_us);
                if (nav->restore_idx == NULL || nav->restore_us == NULL) {
                    fprintf(stderr, "rsm-nav: out of memory\n");
                    exit(1);
                }
            }
            nav->restore_idx[nav->nrestore] = idx;
            nav->restore_us[nav->nrestore] = orig;
            nav->nrestore++;
        }
        p = strchr(p, '\n');
        if (p != NULL) {
            ++p;
        }
    }
}

/* A capture metadata value that must be a positive number; 0 or -1 (said why). */
static int positive_meta(const char *path, const char *key, const char *text, float *out)
{
    char *end;
    const float v = strtof(text, &end);
    if (end == text || !isfinite(v) || !(v > 0.0f)) {
        fprintf(stderr, "rsm-nav: %s: %s is '%s', not a positive number (give --ticks-per-m / --wheel-base)\n",
                path, key, text);
        return -1;
    }
    *out = v;
    return 0;
}

static int run_capture(nav_t *nav, const char *path, const nav_sink_t *sink, const nav_live_options_t *lidar)
{
    static cap_reader reader;
    static nav_devices_t dev;
    static uint8_t buf[CAP_MAX_CHUNK];
    nav_feed_t feed[2];
    rsm_link_t link[2];
    rsm_clock_t clock[2];
    FILE *fp = fopen(path, "rb");
    int robot_id = -1;
    int laser_id = -1;
    nav_laser_kind_t kind = NAV_LASER_LMS;
    size_t i;
    int rc;
    int status;
    const char *v;
    /* Steps of the capture's clock the reader delivered (docs/capture.md,
     * "Far ahead", "Stepped back"): the drivers' time carries on across each
     * from where it was, as stamp_repair does for a CARMEN log's jump. */
    int have_prev = 0;
    uint64_t prev_us = 0;
    uint64_t prev_clock_us = 0;
    uint64_t steps_back = 0;
    uint64_t jumps = 0;
    if (fp == NULL) {
        fprintf(stderr, "rsm-nav: cannot open %s: %s\n", path, strerror(errno));
        return 1;
    }
    if (cap_open(&reader, fp, 1) != CAP_OK) {
        fprintf(stderr, "rsm-nav: %s is not a readable capture: %s\n", path, reader.error);
        fclose(fp);
        return 1;
    }
    for (i = 0; i < reader.n_channels; ++i) {
        if (reader.channels[i].protocol == CAP_PROTO_ARIA && robot_id < 0) {
            robot_id = reader.channels[i].id;
        } else if (reader.channels[i].protocol == CAP_PROTO_LMS2XX && laser_id < 0) {
            laser_id = reader.channels[i].id;
        } else if ((reader.channels[i].protocol == CAP_PROTO_LD06 ||
                    reader.channels[i].protocol == CAP_PROTO_RPLIDAR) && laser_id < 0) {
            /* rsm-record --port NAME=DEV@BAUD:ld06|rplidar tags the lidar's channel */
            laser_id = reader.channels[i].id;
            kind = reader.channels[i].protocol == CAP_PROTO_LD06 ? NAV_LASER_LD06 : NAV_LASER_RPLIDAR;
        }
    }
    /* rsm-convert --lidar: the laser is a spinning lidar's raw stream. */
    if (laser_id < 0 && (v = meta(&reader, "laser.model")) != NULL &&
        (strcmp(v, "ld06") == 0 || strcmp(v, "rplidar") == 0)) {
        kind = strcmp(v, "ld06") == 0 ? NAV_LASER_LD06 : NAV_LASER_RPLIDAR;
        for (i = 0; i < reader.n_channels; ++i) {
            if (reader.channels[i].protocol == CAP_PROTO_RAW && strcmp(reader.channels[i].name, "lidar") == 0) {
                laser_id = reader.channels[i].id;
            }
        }
    }
    /* Geometry recorded with the capture, unless given on the command line. */
    if ((v = meta(&reader, "robot.ticks_per_m")) != NULL && nav->cfg.odometry.ticks_per_m_left == 0.0f) {
        if (positive_meta(path, "robot.ticks_per_m", v, &nav->cfg.odometry.ticks_per_m_left) != 0) {
            cap_close(&reader);
            fclose(fp);
            return 1;
        }
        nav->cfg.odometry.ticks_per_m_right = nav->cfg.odometry.ticks_per_m_left;
    }
    if ((v = meta(&reader, "robot.wheel_base_m")) != NULL && nav->cfg.odometry.wheel_base_m == 0.0f &&
        positive_meta(path, "robot.wheel_base_m", v, &nav->cfg.odometry.wheel_base_m) != 0) {
        cap_close(&reader);
        fclose(fp);
        return 1;
    }
    /* The table is per LMS telegram; a lidar's scans are its turns, stamped mid-turn. */
    if (kind == NAV_LASER_LMS && (v = meta(&reader, "convert.clamped")) != NULL) {
        load_restore_table(nav, v);
    }
    {
        double x0[3] = {0.0, 0.0, 0.0};
        if ((v = meta(&reader, "robot.initial_pose")) != NULL &&
            sscanf(v, "%lf %lf %lf", &x0[0], &x0[1], &x0[2]) != 3) {
            x0[0] = x0[1] = x0[2] = 0.0;
        }
        if (nav->cfg.odometry.ticks_per_m_left == 0.0f) {
            const rsm_odometry_config_t d = rsm_odometry_config_default();
            nav->cfg.odometry.ticks_per_m_left = d.ticks_per_m_left;
            nav->cfg.odometry.ticks_per_m_right = d.ticks_per_m_right;
        }
        if (nav->cfg.odometry.wheel_base_m == 0.0f) {
            nav->cfg.odometry.wheel_base_m = rsm_odometry_config_default().wheel_base_m;
        }
        if (nav_start(nav, x0, "the capture's robot.initial_pose") != 0) {
            cap_close(&reader);
            fclose(fp);
            return 2;
        }
    }
    /* The drivers, listen-only, decode the recorded bytes (one path with
     * live mode), each from its own memory link whose clock reads the
     * record's time. */
    nav_devices_defaults(&dev, 1, nav->quiet);
    nav_devices_odometry(&dev, &nav->cfg.odometry);
    dev.rcfg.deskew = (uint8_t)(lidar->deskew != 0);
    if (kind != NAV_LASER_LMS &&
        nav_devices_lidar(&dev, kind, &lidar->mount, lidar->upside_down, lidar->lidar_keep) != 0) {
        cap_close(&reader);
        fclose(fp);
        return 1;
    }
    for (i = 0; i < 2; ++i) {
        nav_feed_init(&feed[i], &link[i], &clock[i]);
        if (nav_devices_start(&dev, i == 0, &link[i], &clock[i]) != 0) {
            cap_close(&reader);
            fclose(fp);
            return 1;
        }
    }
    status = 0;
    for (;;) {
        cap_record rec;
        rc = cap_next(&reader, &rec, buf, sizeof buf);
        if (rc == CAP_END) {
            break;
        }
        if (rc == CAP_ERR_IO) {
            /* Sticky: stop here; what was decoded so far is still flushed
             * and written by the caller. */
            fprintf(stderr, "rsm-nav: cannot read %s: %s\n", path, cap_error_text(&reader));
            status = 1;
            break;
        }
        if (rc != CAP_OK) {
            continue; /* lenient: counted in reader.count */
        }
        if (have_prev && (rec.timestamp_us < prev_us || rec.timestamp_us - prev_us > CAP_MAX_STEP_US)) {
            /* No time passes across the step: otherwise the drivers would
             * see the clock go back, or an hour's silence that ends a
             * spinning lidar's stream. */
            if (rec.timestamp_us < prev_us) {
                steps_back++;
            } else {
                jumps++;
            }
            nav->cap_base_us = prev_clock_us - rec.timestamp_us;
        }
        have_prev = 1;
        prev_us = rec.timestamp_us;
        prev_clock_us = rec.timestamp_us + nav->cap_base_us;
        if (rec.direction != CAP_RX) {
            continue;
        }
        if ((int)rec.channel == robot_id) {
            nav_devices_feed(&dev, 1, &feed[0], buf, rec.length, prev_clock_us, sink);
        } else if ((int)rec.channel == laser_id) {
            nav_devices_feed(&dev, 0, &feed[1], buf, rec.length, prev_clock_us, sink);
        }
    }
    nav_devices_flush(&dev, sink); /* a turn may still wait for odometry */
    printf("rsm-nav summary\n");
    printf("  source          capture %s\n", path);
    printf("  records         %llu (corrupt %llu, truncated %llu, out of order %llu, unknown channel %llu;"
           " %llu bytes skipped, %llu checked by CRC)\n",
           (unsigned long long)reader.count.records, (unsigned long long)reader.count.corrupt,
           (unsigned long long)reader.count.truncated, (unsigned long long)reader.count.out_of_order,
           (unsigned long long)reader.count.unknown_channel, (unsigned long long)reader.count.skipped_bytes,
           (unsigned long long)reader.count.crc_bytes);
    if (steps_back != 0u || jumps != 0u) {
        printf("  capture clock   %llu steps back, %llu jumps over an hour ahead (the time carried on across"
               " each; the first record after each, not trusted alone, counted out of order)\n",
               (unsigned long long)steps_back, (unsigned long long)jumps);
    }
    printf("  robot link      %u encoder packets, %u other; checksum errors %u, bytes skipped %u\n",
           (unsigned)dev.robot.stats.encoder_packets,
           (unsigned)(dev.robot.stats.sips + dev.robot.stats.config_packets + dev.robot.stats.unknown_packets),
           (unsigned)dev.robot.parser.stats.checksum_errors, (unsigned)dev.robot.parser.stats.bytes_skipped);
    if (kind == NAV_LASER_LMS) {
        printf("  laser link      %u scans, %u bad, %u other; CRC errors %u, bytes skipped %u\n",
               (unsigned)dev.laser.stats.scans, (unsigned)dev.laser.stats.bad_scans,
               (unsigned)dev.laser.stats.unexpected, (unsigned)dev.laser.parser.stats.crc_errors,
               (unsigned)dev.laser.parser.stats.bytes_skipped);
    } else if (kind == NAV_LASER_LD06) {
        printf("  lidar link      %u packets, %u points, %u turns (%u partial); CRC errors %u, bytes skipped %u\n",
               (unsigned)dev.ld06.stats.packets, (unsigned)dev.ld06.stats.points, (unsigned)dev.rev.stats.scans,
               (unsigned)dev.rev.stats.partial, (unsigned)dev.ld06.parser.stats.crc_errors,
               (unsigned)dev.ld06.parser.stats.bytes_skipped);
    } else {
        const rsm_rplidar_stats_t *ps = &dev.rplidar.parser.stats;
        printf("  lidar link      %u descriptors, %u nodes, %u capsules, %u points, %u turns (%u partial);"
               " bad nodes %u, checksum errors %u, bytes skipped %u\n",
               (unsigned)ps->descriptors, (unsigned)ps->nodes, (unsigned)ps->capsules,
               (unsigned)dev.rplidar.stats.points, (unsigned)dev.rev.stats.scans, (unsigned)dev.rev.stats.partial,
               (unsigned)ps->bad_nodes, (unsigned)ps->checksum_errors, (unsigned)ps->bytes_skipped);
    }
    cap_close(&reader);
    if (fclose(fp) != 0 && status == 0) {
        fprintf(stderr, "rsm-nav: error closing %s: %s\n", path, strerror(errno));
        status = 1;
    }
    return status;
}

static const char *method_name(rsm_method_t m)
{
    switch (m) {
    case RSM_METHOD_MAP: return "rsm (persistent map)";
    case RSM_METHOD_PAPER: return "paper (key points + RANSAC)";
    case RSM_METHOD_ICP: return "icp";
    default: return "odometry";
    }
}

/* The --method word that selects m. */
static const char *method_key(rsm_method_t m)
{
    switch (m) {
    case RSM_METHOD_MAP: return "rsm";
    case RSM_METHOD_PAPER: return "paper";
    case RSM_METHOD_ICP: return "icp";
    default: return "odometry";
    }
}

static void print_mount(const nav_t *nav)
{
    const rsm_pose_t *m = &nav->cfg.laser_mount;
    printf("  laser mount     x %.3f m, y %.3f m, theta %.4f rad, %s (%s%s%s)\n", (double)m->x, (double)m->y,
           (double)m->theta, nav->cfg.laser_upside_down ? "upside down (flag)" : "upright",
           nav->mount_source != NULL ? nav->mount_source : "default zero", nav->mount_note[0] != '\0' ? "; " : "",
           nav->mount_note);
    if (nav->mount_disagree != 0u) {
        printf("                  %llu later laser poses in the log differ from the first by more than"
               " %.0f mm / %.3f rad (the first kept)\n",
               (unsigned long long)nav->mount_disagree, (double)NAV_MOUNT_TOL_M * 1000.0, (double)NAV_MOUNT_TOL_RAD);
    }
}

/* Peak resident memory of this program, where the system tells it
 * (Linux: VmHWM; getrusage would count the parent's memory at the fork),
 * then the most this program's own blocks held (tools/nav/heap.h): the
 * resident figure moves with the allocator, a sanitizer and the machine's
 * load, the count does not. */
static void print_peak_memory(void)
{
    char line[128];
    FILE *f = fopen("/proc/self/status", "r");
    while (f != NULL && fgets(line, sizeof line, f) != NULL) {
        unsigned long kib;
        if (sscanf(line, "VmHWM: %lu kB", &kib) == 1) {
            printf("  memory          peak %lu KiB resident\n", kib);
            break;
        }
    }
    if (f != NULL) {
        fclose(f);
    }
    printf("  heap            peak %lu bytes held by rsm-nav's own blocks\n", (unsigned long)nav_heap_peak());
}

/* Median and 95th percentile of the per-scan wall times, in seconds. */
static void time_stats(nav_t *nav, double *median, double *p95)
{
    /* The k-th smallest (from 0) lies in the bin where the running count
     * passes k: the same ranks as a sorted array, to a bin's width. */
    const uint64_t k50 = (uint64_t)(nav->ntimes / 2u);
    const uint64_t k95 = (uint64_t)((nav->ntimes * 95u) / 100u < nav->ntimes ? (nav->ntimes * 95u) / 100u
                                                                             : nav->ntimes - 1u);
    uint64_t seen = 0;
    size_t b;
    int have50 = 0;
    *median = 0.0;
    *p95 = 0.0;
    if (nav->ntimes == 0u) {
        return;
    }
    for (b = 0; b < NAV_TIME_BINS; ++b) {
        seen += nav->time_bins[b];
        if (!have50 && seen > k50) {
            *median = bin_time(b);
            have50 = 1;
        }
        if (seen > k95) {
            *p95 = bin_time(b);
            return;
        }
    }
}

/* --summary-json: what the printed summary says, for programs (the bench).
 * Keys: method, scans, outcomes {name: count}, tracking {tracking,
 * uncertain, lost: scans that left the estimate so; final: the state at
 * the end}, median_us, p95_us,
 * timestamps {clamped, odd, jumps}, drops {nan, too_short, too_long, occluded},
 * alignment {...} (capture and live modes), odometry_calibrations, and for
 * the persistent map tmap {writes, tiles [per level], taken, evicted,
 * dropped, freed, behind, unconfirmed}, recovery {searches, taken, ambiguous},
 * odometry_faults {caught_up, refuted, recounted} (odometry steps the
 * scans judged faulty: motion matching had already found, reported again
 * after a stall; steps the scan fitted far better without; and apart,
 * matches taken back because odometry counted from before them fitted far
 * better),
 * unpinned (matches that left the position along a corridor to odometry),
 * contradicted (scans whose beams passed through the map's walls: refused
 * or not written, conflict_max),
 * heading_correction {turn, drift_rad_per_m, scans} and distance_correction
 * {scale, scans} (what the odometry calibration learnt; the distance's is
 * 0 from 0 scans while it is off).
 * Returns 0, or -1 if the file cannot be written. */
static int write_summary_json(nav_t *nav, const char *path)
{
    const rsm_localizer_counters_t *c = &nav->loc.counters;
    double median;
    double p95;
    int o;
    int first = 1;
    FILE *f = fopen(path, "w");
    if (f == NULL) {
        return -1;
    }
    time_stats(nav, &median, &p95);
    fprintf(f, "{\n  \"method\": \"%s\",\n  \"scans\": %u,\n  \"outcomes\": {", method_key(nav->cfg.method),
            (unsigned)c->scans);
    for (o = 0; o < RSM_SCAN_OUTCOMES; ++o) {
        if (c->outcome[o] != 0) {
            fprintf(f, "%s\"%s\": %u", first ? "" : ", ", rsm_outcome_name((rsm_outcome_t)o), (unsigned)c->outcome[o]);
            first = 0;
        }
    }
    fprintf(f, "},\n  \"tracking\": {\"tracking\": %u, \"uncertain\": %u, \"lost\": %u, \"final\": \"%s\"}",
            (unsigned)c->track[RSM_TRACK_TRACKING], (unsigned)c->track[RSM_TRACK_UNCERTAIN],
            (unsigned)c->track[RSM_TRACK_LOST], rsm_track_name(rsm_localizer_track(&nav->loc)));
    fprintf(f, ",\n  \"median_us\": %.1f,\n  \"p95_us\": %.1f,\n", median * 1e6, p95 * 1e6);
    fprintf(f, "  \"heap_peak_bytes\": %lu,\n", (unsigned long)nav_heap_peak());
    fprintf(f, "  \"timestamps\": {\"clamped\": %llu, \"odd\": %llu, \"jumps\": %llu},\n",
            (unsigned long long)nav->repair.clamped, (unsigned long long)nav->repair.odd_stamps,
            (unsigned long long)nav->repair.time_jumps);
    fprintf(f, "  \"drops\": {\"nan\": %u, \"too_short\": %u, \"too_long\": %u, \"occluded\": %u},\n",
            (unsigned)c->drops.nan, (unsigned)c->drops.too_short, (unsigned)c->drops.too_long, (unsigned)c->occluded);
    fprintf(f, "  \"odometry_calibrations\": %u,\n", nav->calibrations);
    {
        const rsm_sync_counters_t *a = &nav->sync.counters;
        fprintf(f,
                "  \"alignment\": {\"scans\": %u, \"encoders\": %u, \"interpolated\": %u, \"exact\": %u, "
                "\"late\": %u, \"timed_out\": %u, \"superseded\": %u, \"encoder_backwards\": %u, "
                "\"encoder_overflow\": %u, \"restarts\": %u, \"blind_predictions\": %u},\n"
                "  \"predictions\": %u",
                (unsigned)a->scans, (unsigned)a->encoders, (unsigned)a->interpolated, (unsigned)a->exact,
                (unsigned)a->late, (unsigned)a->timed_out, (unsigned)a->superseded, (unsigned)a->encoder_backwards,
                (unsigned)a->encoder_overflow, (unsigned)a->restarts, (unsigned)a->blind_predictions,
                (unsigned)nav->loc.counters.motions);
    }
    if (nav->cfg.method == RSM_METHOD_MAP && nav->initialised) {
        const rsm_tmap_t *m = &nav->loc.state.persistent.map;
        uint32_t level;
        fprintf(f, ",\n  \"tmap\": {\"writes\": %u, \"tiles\": [", (unsigned)m->counters.updates);
        for (level = 0; level < m->cfg.levels; ++level) {
            fprintf(f, "%s%u", level > 0u ? ", " : "", (unsigned)rsm_tmap_tiles(m, level));
        }
        fprintf(f, "], \"taken\": %u, \"evicted\": %u, \"dropped\": %u, \"freed\": %u, \"behind\": %u, "
                   "\"unconfirmed\": %u, \"stored\": %u, \"fetched\": %u, \"unstored\": %u, \"store_tiles\": %u},\n  \"recovery\": {\"searches\": %u, \"taken\": %u, \"ambiguous\": %u},\n"
                   "  \"unpinned\": %u,\n  \"contradicted\": %u",
                (unsigned)m->counters.allocated, (unsigned)m->counters.evicted, (unsigned)m->counters.dropped,
                (unsigned)m->counters.freed, (unsigned)m->counters.behind, (unsigned)c->unconfirmed,
                (unsigned)m->counters.stored, (unsigned)m->counters.fetched, (unsigned)m->counters.unstored,
                m->store != NULL ? (unsigned)m->store->count(m->store->ctx) : 0u, (unsigned)c->searches, (unsigned)c->recovered, (unsigned)c->ambiguous, (unsigned)c->unpinned,
                (unsigned)c->contradicted);
        fprintf(f, ",\n  \"fit\": %.4f", (double)nav->loc.state.persistent.fit);
        fprintf(f, ",\n  \"global\": {\"searches\": %u, \"found\": %u, \"not_proven\": %u, \"work\": %u, "
                   "\"max_work_per_scan\": %u, \"first_trusted_scan\": %llu, \"first_trusted_stamp\": %.6f, "
                   "\"grid_bytes\": %lu}",
                (unsigned)c->global_searches, (unsigned)c->global_found, (unsigned)c->global_ambiguous,
                (unsigned)c->global_work, (unsigned)nav->max_search_work, (unsigned long long)nav->first_trusted,
                nav->first_trusted_s, nav->search_mem != NULL ? nav->search_bytes : (unsigned long)RSM_GLOBAL_GRID_BYTES);
        if (nav->load_map != NULL) {
            fprintf(f, ",\n  \"loaded_map\": {\"bytes\": %u, \"tiles\": %u}", (unsigned)nav->loaded.bytes,
                    (unsigned)nav->loaded.tiles);
        }
        fprintf(f, ",\n  \"odometry_faults\": {\"caught_up\": %u, \"refuted\": %u, \"recounted\": %u}",
                (unsigned)c->caught_up, (unsigned)c->refuted, (unsigned)c->recounted);
        fprintf(f, ",\n  \"heading_correction\": {\"turn\": %.5f, \"drift_rad_per_m\": %.5f, \"scans\": %u}",
                (double)nav->loc.odo_cal.k_turn, (double)nav->loc.odo_cal.k_drift, (unsigned)nav->loc.odo_cal.used);
        fprintf(f, ",\n  \"distance_correction\": {\"scale\": %.5f, \"scans\": %u}",
                (double)nav->loc.odo_cal.k_scale, (unsigned)nav->loc.odo_cal.scale_used);
    }
    fprintf(f, "\n}\n");
    return fclose(f) == 0 ? 0 : -1;
}

static void print_summary(nav_t *nav)
{
    const rsm_localizer_counters_t *c = &nav->loc.counters;
    double median;
    double p95;
    int o;
    time_stats(nav, &median, &p95);
    printf("  method          %s\n", method_name(nav->cfg.method));
    print_mount(nav);
    if (nav->cfg.method == RSM_METHOD_MAP) {
        const rsm_tmap_t *m = &nav->loc.state.persistent.map;
        uint32_t level;
        printf("  persistent map  %u writes, tiles ", (unsigned)m->counters.updates);
        for (level = 0; level < m->cfg.levels; ++level) {
            printf("%s%u", level > 0u ? "/" : "", (unsigned)rsm_tmap_tiles(m, level));
        }
        printf(" per level, %u taken, %u evicted, %u returns dropped\n", (unsigned)m->counters.allocated,
               (unsigned)m->counters.evicted, (unsigned)m->counters.dropped);
        printf("  map writes      %u tiles cleared and freed, %u returns behind walls, %u unconfirmed\n",
               (unsigned)m->counters.freed, (unsigned)m->counters.behind, (unsigned)c->unconfirmed);
        if (m->store != NULL) {
            printf("  tile store      %u tiles held, %u let go into it, %u taken back, %u lost (full)\n",
                   (unsigned)m->store->count(m->store->ctx), (unsigned)m->counters.stored,
                   (unsigned)m->counters.fetched, (unsigned)m->counters.unstored);
        }
        printf("  recovery        %u searches, %u taken, %u refused as ambiguous\n", (unsigned)c->searches,
               (unsigned)c->recovered, (unsigned)c->ambiguous);
        if (nav->load_map != NULL) {
            if (nav->loaded.bytes > 0u) {
                printf("  loaded map      %s: %u bytes, %u tiles%s\n", nav->load_map, (unsigned)nav->loaded.bytes,
                       (unsigned)nav->loaded.tiles, nav->cfg.map_frozen ? ", frozen" : ", updated");
            } else {
                printf("  loaded map      %s: a ROS map, %u tiles%s\n", nav->load_map, (unsigned)nav->loaded.tiles,
                       nav->cfg.map_frozen ? ", frozen" : ", updated");
            }
        }
        if (c->global_searches > 0u || nav->global) {
            printf("  global search   %u begun, %u proved a pose, %u did not; %u cells read, at most %u"
                   " in a scan; grids in %lu bytes\n",
                   (unsigned)c->global_searches, (unsigned)c->global_found, (unsigned)c->global_ambiguous,
                   (unsigned)c->global_work, (unsigned)nav->max_search_work,
                   nav->search_mem != NULL ? nav->search_bytes : (unsigned long)RSM_GLOBAL_GRID_BYTES);
            /* Only a run begun with no pose (--global) waits for its
             * first one; a search after tracking was lost says so above. */
            if (nav->global && nav->first_trusted > 0u) {
                printf("  first pose      scan %llu (%.3f s)\n", (unsigned long long)nav->first_trusted,
                       nav->first_trusted_s);
            } else if (nav->global) {
                printf("  first pose      none: no pose was proven\n");
            }
        }
        printf("  odometry faults %u steps after a stall counted once (caught up), %u refuted by the scans;"
               " %u matches taken back (odometry was right)\n",
               (unsigned)c->caught_up, (unsigned)c->refuted, (unsigned)c->recounted);
        printf("  unpinned        %u matches left the position along the scan's surfaces to odometry\n",
               (unsigned)c->unpinned);
        printf("  contradicted    %u scans whose beams passed through the map's walls, not written\n",
               (unsigned)c->contradicted);
        printf("  occluded        %u returns behind a surface their neighbours span, dropped\n",
               (unsigned)c->occluded);
        if (nav->cfg.odometry_cal.memory > 0.0f) {
            printf("  odometry turns  corrected by %+.2f %%, heading drift %+.3f deg/m (from %u scans)\n",
                   (double)(nav->loc.odo_cal.k_turn * 100.0f), (double)(nav->loc.odo_cal.k_drift * 57.29578f),
                   (unsigned)nav->loc.odo_cal.used);
        }
        if (nav->cfg.odometry_cal.memory > 0.0f && nav->cfg.odometry_cal.max_scale > 0.0f) {
            printf("  odometry travel corrected by %+.2f %% (from %u scans)\n",
                   (double)(nav->loc.odo_cal.k_scale * 100.0f), (unsigned)nav->loc.odo_cal.scale_used);
        }
    }
    printf("  timestamps      %llu clamped (went backwards), %llu odd (far from both neighbours: replaced),"
           " %llu jumps of the clock\n",
           (unsigned long long)nav->repair.clamped, (unsigned long long)nav->repair.odd_stamps,
           (unsigned long long)nav->repair.time_jumps);
    printf("  scans           %u\n", (unsigned)c->scans);
    printf("  tracking        %u scans tracking, %u uncertain, %u lost; %s at the end\n",
           (unsigned)c->track[RSM_TRACK_TRACKING], (unsigned)c->track[RSM_TRACK_UNCERTAIN],
           (unsigned)c->track[RSM_TRACK_LOST], rsm_track_name(rsm_localizer_track(&nav->loc)));
    for (o = 0; o < RSM_SCAN_OUTCOMES; ++o) {
        if (c->outcome[o] != 0) {
            printf("    %-14s %u\n", rsm_outcome_name((rsm_outcome_t)o), (unsigned)c->outcome[o]);
        }
    }
    if (nav->sync.counters.scans > 0u || nav->sync.counters.encoders > 0u) {
        const rsm_sync_counters_t *a = &nav->sync.counters;
        printf("  alignment       %u interpolated, %u exact, %u late, %u timed out, %u superseded;\n"
               "                  encoder stamps backwards %u, applied early %u\n",
               (unsigned)a->interpolated, (unsigned)a->exact, (unsigned)a->late, (unsigned)a->timed_out,
               (unsigned)a->superseded, (unsigned)a->encoder_backwards, (unsigned)a->encoder_overflow);
    }
    /* Capture and live modes compose the odometry between scans (rsm/sync.h):
     * one prediction per scan, as --carmen makes. */
    printf("  predictions     %u odometry predictions", (unsigned)nav->loc.counters.motions);
    if (nav->sync.counters.blind_predictions > 0u) {
        printf(", %u of them with no scan (after max_travel_m of wheel travel, or before a half turn)",
               (unsigned)nav->sync.counters.blind_predictions);
    }
    printf("\n");
    if (nav->loc.odo.implausible != 0u || nav->loc.odo.relatched != 0u || nav->loc.ekf.lost != 0u) {
        printf("  odometry        %u implausible increments refused, %u counter restarts taken up,"
               " %u predictions lost (covariance reset)\n",
               (unsigned)nav->loc.odo.implausible, (unsigned)nav->loc.odo.relatched, (unsigned)nav->loc.ekf.lost);
    }
    printf("  readings dropped: nan %u, too short %u, too long %u\n", (unsigned)c->drops.nan,
           (unsigned)c->drops.too_short, (unsigned)c->drops.too_long);
    printf("  time per scan   median %.1f us, p95 %.1f us (this machine, wall clock)\n", median * 1e6, p95 * 1e6);
    print_peak_memory();
}

/* ---- command line ------------------------------------------------------------ */

enum {
    OPT_CARMEN = 256, OPT_CAPTURE, OPT_ROBOT, OPT_LMS, OPT_LIDAR, OPT_LIDAR_KEEP, OPT_NO_DESKEW,
    OPT_ROBOT_BAUD, OPT_LMS_BAUD, OPT_LISTEN, OPT_SECONDS, OPT_IDLE_EXIT, OPT_LOST_EXIT, OPT_TICKS_PER_M, OPT_WHEEL_BASE,
    OPT_INITIAL_POSE, OPT_LASER_POSE, OPT_UPSIDE_DOWN, OPT_TRAJECTORY, OPT_SUMMARY_JSON, OPT_TUM, OPT_SCAN_LOG, OPT_EVENTS,
    OPT_MAP, OPT_METHOD, OPT_SET, OPT_FOV179, OPT_ODOM_LINES, OPT_QUIET, OPT_SAVE_MAP, OPT_LOAD_MAP, OPT_GLOBAL, OPT_FREEZE_MAP,
    OPT_SKIP_SECONDS, OPT_SCANS, OPT_GLOBAL_NEAR, OPT_TILE_STORE, OPT_SEARCH_MEMORY
};

/* --lidar, --initial-pose and --laser-pose take more than one value: the
 * table gives the first (or none) and the parser reads the rest; "+" in the
 * short options stops at the first argument that is not an option, so that
 * a value such as -0.05 is never taken for one. */
static const struct option nav_options[] = {
    {"carmen", required_argument, NULL, OPT_CARMEN},
    {"capture", required_argument, NULL, OPT_CAPTURE},
    {"robot", required_argument, NULL, OPT_ROBOT},
    {"lms", required_argument, NULL, OPT_LMS},
    {"lidar", required_argument, NULL, OPT_LIDAR},
    {"lidar-keep", required_argument, NULL, OPT_LIDAR_KEEP},
    {"no-deskew", no_argument, NULL, OPT_NO_DESKEW},
    {"robot-baud", required_argument, NULL, OPT_ROBOT_BAUD},
    {"lms-baud", required_argument, NULL, OPT_LMS_BAUD},
    {"listen", no_argument, NULL, OPT_LISTEN},
    {"seconds", required_argument, NULL, OPT_SECONDS},
    {"idle-exit", required_argument, NULL, OPT_IDLE_EXIT},
    {"lost-exit", required_argument, NULL, OPT_LOST_EXIT},
    {"ticks-per-m", required_argument, NULL, OPT_TICKS_PER_M},
    {"wheel-base", required_argument, NULL, OPT_WHEEL_BASE},
    {"initial-pose", no_argument, NULL, OPT_INITIAL_POSE},
    {"laser-pose", no_argument, NULL, OPT_LASER_POSE},
    {"upside-down", no_argument, NULL, OPT_UPSIDE_DOWN},
    {"trajectory", required_argument, NULL, OPT_TRAJECTORY},
    {"summary-json", required_argument, NULL, OPT_SUMMARY_JSON},
    {"tum", required_argument, NULL, OPT_TUM},
    {"scan-log", required_argument, NULL, OPT_SCAN_LOG},
    {"events", required_argument, NULL, OPT_EVENTS},
    {"map", required_argument, NULL, OPT_MAP},
    {"method", required_argument, NULL, OPT_METHOD},
    {"set", required_argument, NULL, OPT_SET},
    {"fov179", no_argument, NULL, OPT_FOV179},
    {"odom-lines", no_argument, NULL, OPT_ODOM_LINES},
    {"quiet", no_argument, NULL, OPT_QUIET},
    {"save-map", required_argument, NULL, OPT_SAVE_MAP},
    {"load-map", required_argument, NULL, OPT_LOAD_MAP},
    {"global", no_argument, NULL, OPT_GLOBAL},
    {"freeze-map", no_argument, NULL, OPT_FREEZE_MAP},
    {"skip-seconds", required_argument, NULL, OPT_SKIP_SECONDS},
    {"scans", required_argument, NULL, OPT_SCANS},
    {"global-near", required_argument, NULL, OPT_GLOBAL_NEAR},
    {"tile-store", required_argument, NULL, OPT_TILE_STORE},
    {"search-memory", required_argument, NULL, OPT_SEARCH_MEMORY},
    {"help", no_argument, NULL, 'h'},
    {NULL, 0, NULL, 0}
};

/* An argument the parser cannot place (or an option whose value is missing):
 * named, then the usage, exit status 2. */
static int unexpected(const char *arg)
{
    fprintf(stderr, "rsm-nav: unexpected argument '%s'\n", arg);
    usage(stderr);
    return 2;
}

/* Three finite numbers x y theta into *pose; -1 (pose partly written) if
 * any is not a whole number. */
static int parse_pose(char *const *v, rsm_pose_t *pose)
{
    char *e1;
    char *e2;
    char *e3;
    pose->x = strtof(v[0], &e1);
    pose->y = strtof(v[1], &e2);
    pose->theta = strtof(v[2], &e3);
    if (e1 == v[0] || e2 == v[1] || e3 == v[2] || *e1 != '\0' || *e2 != '\0' || *e3 != '\0' ||
        !isfinite(pose->x) || !isfinite(pose->y) || !isfinite(pose->theta)) {
        return -1;
    }
    return 0;
}

/* An output file named on the command line, or NULL after saying why. */
static FILE *open_output(const char *path)
{
    FILE *f = fopen(path, "w");
    if (f == NULL) {
        fprintf(stderr, "rsm-nav: cannot write %s: %s\n", path, strerror(errno));
    }
    return f;
}

int main(int argc, char **argv)
{
    static nav_t nav; /* the localizer is about 122 KiB: keep it off the stack */
    const char *carmen = NULL;
    const char *capture = NULL;
    const char *trajectory = NULL;
    const char *summary_json = NULL;
    nav_live_options_t live;
    nav_sink_t sink;
    float ticks_per_m = 0.0f;
    float wheel_base = 0.0f;
    int fov179 = 0;
    int odom_lines = 0;
    int never_back = 0;
    int rc;
    int opt;
    int li = 0;

    memset(&live, 0, sizeof live);
    live.lidar_keep = 1u;
    nav.cfg = rsm_localizer_config_default();
    nav.search_bytes = (unsigned long)RSM_GLOBAL_LEND_BYTES;
    opterr = 0; /* this program words its own messages */
    while ((opt = getopt_long(argc, argv, "+:h", nav_options, &li)) != -1) {
        const char *name = opt == '?' || opt == ':' ? argv[optind - 1] : nav_options[li].name;
        switch (opt) {
        case OPT_CARMEN:
            carmen = optarg;
            break;
        case OPT_CAPTURE:
            capture = optarg;
            break;
        case OPT_ROBOT:
            live.robot = optarg;
            break;
        case OPT_LMS:
            live.lms = optarg;
            break;
        case OPT_LIDAR: /* --lidar KIND DEV */
            if (optind >= argc) {
                return unexpected("--lidar");
            }
            if (strcmp(optarg, "ld06") == 0) {
                live.laser = NAV_LASER_LD06;
            } else if (strcmp(optarg, "rplidar") == 0) {
                live.laser = NAV_LASER_RPLIDAR;
            } else {
                fprintf(stderr, "rsm-nav: --lidar takes ld06 or rplidar, not '%s'\n", optarg);
                return 2;
            }
            live.lms = argv[optind++];
            break;
        case OPT_LIDAR_KEEP: {
            const long v = strtol(optarg, NULL, 10);
            if (v < 1 || v > 64) {
                fprintf(stderr, "rsm-nav: --lidar-keep takes 1 to 64, not '%s'\n", optarg);
                return 2;
            }
            live.lidar_keep = (unsigned)v;
            break;
        }
        case OPT_NO_DESKEW:
            nav.no_deskew = 1;
            break;
        case OPT_ROBOT_BAUD:
        case OPT_LMS_BAUD: {
            const long v = strtol(optarg, NULL, 10);
            if (v <= 0) {
                fprintf(stderr, "rsm-nav: bad baud rate '%s'\n", optarg);
                return 2;
            }
            if (opt == OPT_ROBOT_BAUD) {
                live.robot_baud = (uint32_t)v;
            } else {
                live.lms_baud = (uint32_t)v;
            }
            break;
        }
        case OPT_LISTEN:
            live.listen_only = 1;
            break;
        case OPT_SECONDS:
        case OPT_IDLE_EXIT:
        case OPT_LOST_EXIT: {
            const double v = strtod(optarg, NULL);
            if (!(v > 0.0)) {
                fprintf(stderr, "rsm-nav: bad duration '%s'\n", optarg);
                return 2;
            }
            if (opt == OPT_SECONDS) {
                live.seconds = v;
            } else if (opt == OPT_IDLE_EXIT) {
                live.idle_exit_s = v;
            } else {
                live.lost_exit_s = v;
            }
            break;
        }
        case OPT_TICKS_PER_M:
        case OPT_WHEEL_BASE: {
            const float v = strtof(optarg, NULL);
            if (!(v > 0.0f)) {
                fprintf(stderr, "rsm-nav: bad value '%s' for --%s\n", optarg, name);
                return 2;
            }
            if (opt == OPT_TICKS_PER_M) {
                ticks_per_m = v;
            } else {
                wheel_base = v;
            }
            break;
        }
        case OPT_INITIAL_POSE: /* three numbers follow */
            if (optind + 3 > argc) {
                return unexpected(argv[optind - 1]);
            }
            if (parse_pose(argv + optind, &nav.x0) != 0) {
                fprintf(stderr, "rsm-nav: bad --initial-pose\n");
                return 2;
            }
            nav.have_x0 = 1;
            optind += 3;
            break;
        case OPT_LASER_POSE:
            if (optind + 3 > argc) {
                fprintf(stderr, "rsm-nav: --laser-pose needs three numbers: x y theta\n");
                return 2;
            }
            if (parse_pose(argv + optind, &nav.cfg.laser_mount) != 0) {
                fprintf(stderr, "rsm-nav: bad --laser-pose (three numbers: x y theta)\n");
                return 2;
            }
            nav.cfg.laser_mount.theta = rsm_wrap_angle(nav.cfg.laser_mount.theta);
            nav.mount_flag = 1;
            optind += 3;
            break;
        case OPT_UPSIDE_DOWN:
            nav.cfg.laser_upside_down = 1u;
            break;
        case OPT_TRAJECTORY:
            trajectory = optarg;
            break;
        case OPT_SUMMARY_JSON:
            summary_json = optarg;
            break;
        case OPT_TUM:
            if ((nav.tum = open_output(optarg)) == NULL) {
                return 1;
            }
            fprintf(nav.tum, "# timestamp x y z qx qy qz qw (TUM)\n");
            break;
        case OPT_SCAN_LOG:
            if ((nav.scan_log = open_output(optarg)) == NULL) {
                return 1;
            }
            fprintf(nav.scan_log, "# rsm-nav scan log: timestamp[s] outcome tracking odometry recovered fit_ratio "
                                  "cov_xx cov_xy cov_xt cov_yy cov_yt cov_tt\n");
            break;
        case OPT_EVENTS:
            if ((nav.events = open_output(optarg)) == NULL) {
                return 1;
            }
            break;
        case OPT_MAP:
            nav.map_path = optarg;
            break;
        case OPT_METHOD:
            if (strcmp(optarg, "rsm") == 0 || strcmp(optarg, "map") == 0) {
                nav.cfg.method = RSM_METHOD_MAP;
            } else if (strcmp(optarg, "paper") == 0) {
                nav.cfg.method = RSM_METHOD_PAPER;
            } else if (strcmp(optarg, "icp") == 0) {
                nav.cfg.method = RSM_METHOD_ICP;
            } else if (strcmp(optarg, "odometry") == 0) {
                nav.cfg.method = RSM_METHOD_ODOMETRY;
            } else {
                fprintf(stderr, "rsm-nav: unknown method '%s'\n", optarg);
                return 2;
            }
            break;
        case OPT_SET: {
            double top = 0.0;
            const int set = set_option(&nav.cfg, optarg, &top);
            if (set == -2) {
                fprintf(stderr, "rsm-nav: bad --set '%s': a whole number from 0 to %.0f\n", optarg, top);
                return 2;
            }
            if (set == -3) {
                fprintf(stderr, "rsm-nav: unknown key in --set '%s' (rsm-nav --help lists them)\n", optarg);
                return 2;
            }
            if (set == -4) {
                fprintf(stderr, "rsm-nav: bad --set '%s': beyond what a float holds (it would be infinite)\n",
                        optarg);
                return 2;
            }
            if (set != 0) {
                fprintf(stderr, "rsm-nav: bad --set '%s'\n", optarg);
                return 2;
            }
            if (strncmp(optarg, "mount_", 6) == 0) {
                nav.mount_flag = 1;
            }
            break;
        }
        case OPT_FOV179:
            fov179 = 1;
            break;
        case OPT_ODOM_LINES:
            odom_lines = 1;
            break;
        case OPT_QUIET:
            nav.quiet = 1;
            break;
        case OPT_SAVE_MAP:
            nav.save_map = optarg;
            break;
        case OPT_LOAD_MAP:
            nav.load_map = optarg;
            break;
        case OPT_GLOBAL:
            nav.global = 1;
            break;
        case OPT_FREEZE_MAP:
            nav.cfg.map_frozen = 1u;
            break;
        case OPT_SKIP_SECONDS: {
            char *end = NULL;
            const double v = strtod(optarg, &end);
            if (end == optarg || *end != '\0' || !(v >= 0.0) || !isfinite(v)) {
                fprintf(stderr, "rsm-nav: bad --skip-seconds '%s' (seconds, 0 or more)\n", optarg);
                return 2;
            }
            nav.skip_s = v;
            break;
        }
        case OPT_TILE_STORE: {
            char *end = NULL;
            const unsigned long v = strtoul(optarg, &end, 10);
            if (end == optarg || *end != '\0' || optarg[0] == '-' || v > (1ul << 28)) {
                fprintf(stderr, "rsm-nav: bad --tile-store '%s' (tiles, 0 to %lu)\n", optarg, 1ul << 28);
                return 2;
            }
            nav.store_tiles = (uint32_t)v;
            break;
        }
        case OPT_SEARCH_MEMORY: {
            char *end = NULL;
            const unsigned long v = strtoul(optarg, &end, 10);
            if (end == optarg || *end != '\0' || optarg[0] == '-' || (v != 0u && v < (unsigned long)RSM_GLOBAL_GRID_BYTES) ||
                v > (unsigned long)RSM_GLOBAL_MAX_GRID_BYTES) {
                fprintf(stderr, "rsm-nav: bad --search-memory '%s' (bytes: 0, or %lu to %lu)\n", optarg,
                        (unsigned long)RSM_GLOBAL_GRID_BYTES, (unsigned long)RSM_GLOBAL_MAX_GRID_BYTES);
                return 2;
            }
            nav.search_bytes = v;
            break;
        }
        case OPT_GLOBAL_NEAR: {
            char *end = NULL;
            const double v = strtod(optarg, &end);
            if (end == optarg || *end != '\0' || !(v > 0.0 && v <= 1.0e5)) {
                fprintf(stderr, "rsm-nav: bad --global-near '%s' (metres, above 0)\n", optarg);
                return 2;
            }
            nav.global = 1;
            nav.global_near_m = (float)v;
            break;
        }
        case OPT_SCANS: {
            char *end = NULL;
            const unsigned long long v = strtoull(optarg, &end, 10);
            if (end == optarg || *end != '\0' || v == 0u || strchr(optarg, '-') != NULL) {
                fprintf(stderr, "rsm-nav: bad --scans '%s' (a count, 1 or more)\n", optarg);
                return 2;
            }
            nav.max_scans = (uint64_t)v;
            break;
        }
        case 'h':
            usage(stdout);
            return 0;
        default: /* unknown option ('?') or a value missing (':') */
            return unexpected(name);
        }
    }
    if (optind < argc) {
        return unexpected(argv[optind]);
    }
    if (((carmen != NULL) + (capture != NULL) + (live.robot != NULL || live.lms != NULL)) != 1 || trajectory == NULL) {
        fprintf(stderr, "rsm-nav: give exactly one source (--carmen, --capture, or --robot/--lms/--lidar) and"
                        " --trajectory\n");
        usage(stderr);
        return 2;
    }
    if ((nav.global || nav.save_map != NULL || nav.load_map != NULL || nav.cfg.map_frozen || nav.store_tiles > 0u) &&
        nav.cfg.method != RSM_METHOD_MAP) {
        fprintf(stderr, "rsm-nav: --save-map, --load-map, --global, --freeze-map and --tile-store need --method rsm\n");
        return 2;
    }
    if (nav.global && nav.load_map == NULL) {
        fprintf(stderr, "rsm-nav: --global and --global-near search a known map: give it with --load-map\n");
        return 2;
    }
    if (odom_lines && carmen == NULL) {
        fprintf(stderr, "rsm-nav: --odom-lines reads the ODOM lines of a CARMEN log: give it with --carmen\n");
        return 2;
    }
    if ((nav.skip_s > 0.0 && carmen == NULL) || (nav.max_scans > 0u && capture != NULL)) {
        fprintf(stderr, "rsm-nav: --skip-seconds works with --carmen, --scans with --carmen and live\n");
        return 2;
    }
    live.max_scans = nav.max_scans;
    live.quiet = nav.quiet;
    /* Captures and live links carry no mount: the flags or zero (--carmen may take the log's). */
    nav.mount_source = nav.mount_flag ? "flag" : "default zero";
    /* Encoder geometry: command line first, then the capture's, then the defaults. */
    if (carmen == NULL) {
        nav.cfg.odometry.ticks_per_m_left = nav.cfg.odometry.ticks_per_m_right = ticks_per_m;
        nav.cfg.odometry.wheel_base_m = wheel_base;
        if (capture == NULL) {
            const rsm_odometry_config_t d = rsm_odometry_config_default();
            if (ticks_per_m == 0.0f) {
                nav.cfg.odometry.ticks_per_m_left = nav.cfg.odometry.ticks_per_m_right = d.ticks_per_m_left;
            }
            if (wheel_base == 0.0f) {
                nav.cfg.odometry.wheel_base_m = d.wheel_base_m;
            }
        }
    }
    if (hitmap_init(&nav.hits, nav.cfg.grid.cell_m) != 0 && nav.map_path != NULL) {
        fprintf(stderr, "rsm-nav: bad cell size for the map picture\n");
        return 2;
    }
    nav.traj = fopen(trajectory, "w");
    if (nav.traj == NULL) {
        fprintf(stderr, "rsm-nav: cannot write %s: %s\n", trajectory, strerror(errno));
        return 1;
    }
    fprintf(nav.traj, "# rsm-nav trajectory: timestamp[s] x[m] y[m] theta[rad]\n# source: %s\n",
            carmen ? carmen : capture ? capture : "live serial links");
    nav.t_start = now_s();
    sink.ctx = &nav;
    sink.encoder = sink_encoder;
    sink.scan = sink_scan;
    sink.tick = sink_tick;
    sink.calibration = sink_calibration;
    nav.ticks_from_flag = ticks_per_m > 0.0f;
    nav.sync_cfg = rsm_sync_config_default();
    live.mount = nav.cfg.laser_mount;
    live.upside_down = nav.cfg.laser_upside_down != 0u;
    live.odometry = &nav.cfg.odometry;
    live.deskew = !nav.no_deskew;
    nav.live = carmen == NULL && capture == NULL;
    if (nav.live) {
        (void)fflush(nav.traj); /* its header too */
    }
    if (carmen != NULL) {
        rc = run_carmen(&nav, carmen, fov179, odom_lines);
    } else if (capture != NULL) {
        rc = run_capture(&nav, capture, &sink, &live);
    } else {
        rc = nav_live_run(&live, &sink);
        if (rc == NAV_LIVE_NEVER_BACK) {
            /* Said already; what ran is summed up and kept, then the run fails. */
            never_back = 1;
            rc = 0;
        }
    }
    if (nav.initialised) {
        nav.call_t0 = now_s();
        (void)rsm_sync_flush(&nav.sync); /* a scan may still wait for odometry */
    }
    if (carmen == NULL && capture == NULL) {
        if (rc == 0) {
            printf("rsm-nav summary\n");
            printf("  source          live: robot %s, %s %s%s\n", live.robot ? live.robot : "-",
                   live.laser == NAV_LASER_LD06 ? "LD06" : live.laser == NAV_LASER_RPLIDAR ? "RPLIDAR" : "laser",
                   live.lms ? live.lms : "-", live.listen_only ? " (listen-only)" : "");
            printf("  robot link      %llu encoder packets, %u counter restarts (new connections)\n",
                   (unsigned long long)nav.encoders, (unsigned)nav.sync.counters.restarts);
        }
    }
    /* Whatever happened, keep what was written. */
    if (nav.events != NULL && fclose(nav.events) != 0) {
        fprintf(stderr, "rsm-nav: error writing the events file\n");
        rc = rc ? rc : 1;
    }
    if (nav.tum != NULL && fclose(nav.tum) != 0) {
        fprintf(stderr, "rsm-nav: error writing the TUM file\n");
        rc = rc ? rc : 1;
    }
    if (nav.scan_log != NULL && fclose(nav.scan_log) != 0) {
        fprintf(stderr, "rsm-nav: error writing the scan log\n");
        rc = rc ? rc : 1;
    }
    if (fclose(nav.traj) != 0) {
        fprintf(stderr, "rsm-nav: error writing %s\n", trajectory);
        rc = rc ? rc : 1;
    }
    if (rc == 0 && nav.map_path != NULL) {
        double w_m = 0.0;
        double h_m = 0.0;
        const int m = pgm_write_map(nav.map_path, &nav.hits, nav.off_x, nav.off_y, &w_m, &h_m);
        if (m == PGM_TOO_LARGE) {
            fprintf(stderr,
                    "rsm-nav: map %s not written: it would span %.0f m x %.0f m, over the %.0f m the"
                    " picture allows at %.3f m per pixel\n",
                    nav.map_path, w_m, h_m, (double)PGM_MAX_SIDE * (double)nav.hits.res_m,
                    (double)nav.hits.res_m);
            rc = 1;
        } else if (m != 0) {
            fprintf(stderr, "rsm-nav: cannot write map %s: %s\n", nav.map_path, strerror(errno));
            rc = 1;
        }
        if (nav.hits.far != 0u) {
            fprintf(stderr, "rsm-nav: %llu map points %.0e m or more from the origin left out of the picture\n",
                    (unsigned long long)nav.hits.far, (double)PGM_MAX_COORD_M);
        }
    }
    if (rc == 0 && nav.save_map != NULL && nav.initialised && nav_save_map(&nav) != 0) {
        rc = 1;
    }
    if (rc == 0) {
        /* Written before the printed summary, whose timing sort it shares. */
        if (summary_json != NULL && write_summary_json(&nav, summary_json) != 0) {
            fprintf(stderr, "rsm-nav: cannot write %s: %s\n", summary_json, strerror(errno));
            rc = 1;
        }
        print_summary(&nav);
    }
    if (rc == 0 && nav.poses == 0u && (carmen != NULL || capture != NULL || live.lms != NULL)) {
        /* A run that was to make poses and made none is a failure the
         * caller must see (a live run with the robot alone makes none). */
        fprintf(stderr, "rsm-nav: no pose: %s\n",
                nav.global && nav.initialised ? "the global search proved none (--global: no trajectory line"
                                                " before a pose is proven)"
                : carmen != NULL && nav.skip_s > 0.0 && nav.ntimes == 0u
                    ? "the log holds no scan from --skip-seconds on (it is shorter)"
                : carmen != NULL  ? "the log holds no usable laser scan"
                : capture != NULL ? "no scan came out of the capture (its laser channel empty, or its protocol "
                                    "tag not what the bytes are)"
                                  : "no scan arrived on the laser link");
        rc = 1;
    }
    if (rc == 0 && never_back) {
        rc = 1;
    }
    hitmap_free(&nav.hits);
    nav_free(nav.store_tile);
    nav_free(nav.store_index);
    nav_free(nav.restore_idx);
    nav_free(nav.restore_us);
    return rc;
}
