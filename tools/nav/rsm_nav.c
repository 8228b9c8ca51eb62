/* rsm-nav: runs the rsm localizer (or the ICP baseline, or odometry alone)
 * over a CARMEN log and writes the trajectory, the map and a summary.
 *
 *   rsm-nav --carmen LOG [--method rsm|icp|odometry] --trajectory OUT.txt
 *           [--map OUT.pgm] [--set key=value ...] [--quiet]
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "carmen.h"
#include "pgm.h"
#include "rsm/localizer.h"
#include "rsm/status.h"

typedef struct options {
    const char *carmen;
    const char *trajectory;
    const char *map;
    int quiet;
} options_t;

static void usage(FILE *f)
{
    fprintf(f,
            "usage: rsm-nav --carmen LOG [--method rsm|icp|odometry] --trajectory OUT.txt\n"
            "               [--map OUT.pgm] [--fov179] [--set KEY=VALUE]... [--quiet]\n"
            "Runs the localizer over a CARMEN log (FLASER/ROBOTLASER1 scans; odometry from the\n"
            "pose fields of the laser lines) and writes one line per scan: timestamp x y theta.\n"
            "KEY is one of: cell, sigma, rule (0 inside, 1 touch, 2 nearest), min_hits, window,\n"
            "search_sigmas, search_min, search_max, gate, noise (0 residual, 1 fixed), r_min_xy,\n"
            "r_min_theta, inlier_tol, length_tol, iterations, min_support, seed, k_den, nms,\n"
            "max_range, min_range, icp_iterations, icp_pair_dist, trans_per_m, rot_per_rad, rot_per_m,\n"
            "map_on_reject, refine (iterations, 0 = off), refine_sat, refine_scale.\n");
}

static int set_option(rsm_localizer_config_t *c, const char *kv)
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
#define F(name, field) if (strcmp(key, name) == 0) { c->field = (float)v; return 0; }
#define U(name, field, type) if (strcmp(key, name) == 0) { if (v < 0) return -1; c->field = (type)v; return 0; }
    F("cell", grid.cell_m)
    F("sigma", grid.sigma_m)
    U("rule", grid.rule, rsm_grid_rule_t)
    U("min_hits", map_min_hits, uint8_t)
    F("window", match_window_m)
    F("search_sigmas", search_sigmas)
    F("search_min", search_min_m)
    F("search_max", search_max_m)
    F("gate", gate_d2)
    U("noise", noise, rsm_noise_model_t)
    F("r_min_xy", r_min_xy_m)
    F("r_min_theta", r_min_theta_rad)
    F("inlier_tol", ransac.inlier_tol_m)
    F("length_tol", ransac.length_tol_m)
    U("iterations", ransac.max_iterations, uint32_t)
    U("min_support", ransac.min_support, uint32_t)
    U("seed", ransac.seed, uint32_t)
    U("k_den", harris.k_den, int32_t)
    U("nms", harris.nms_radius, int32_t)
    U("min_response", harris.min_response, int32_t)
    F("max_range", limits.max_range_m)
    F("min_range", limits.min_range_m)
    U("icp_iterations", icp.max_iterations, uint16_t)
    F("icp_pair_dist", icp.max_pair_dist_m)
    F("trans_per_m", odometry.sigma_trans_per_m)
    F("rot_per_rad", odometry.sigma_rot_per_rad)
    F("rot_per_m", odometry.sigma_rot_per_m)
    U("map_on_reject", map_on_reject, uint8_t)
    U("refine", refine_iterations, uint32_t)
    U("refine_sat", refine_saturation, uint8_t)
    F("refine_scale", refine_noise_scale)
#undef F
#undef U
    return -1;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a;
    const double y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    static rsm_localizer_t loc; /* about 55 KiB: keep it off the stack */
    static carmen_reader_t reader;
    static carmen_record_t rec;
    static rsm_scan_t scan;
    rsm_localizer_config_t cfg = rsm_localizer_config_default();
    options_t opt = {NULL, NULL, NULL, 0};
    rsm_pose_t x0 = {0.0f, 0.0f, 0.0f};
    rsm_pose_t last_odom = {0.0f, 0.0f, 0.0f};
    int have_odom = 0;
    uint64_t last_us = 0;
    uint64_t clamped = 0;
    FILE *traj;
    hitlist_t hits = {NULL, 0, 0};
    double *times = NULL;
    size_t ntimes = 0;
    size_t cap_times = 0;
    double t_start;
    int i;
    int initialised = 0;

    for (i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *next = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--carmen") == 0 && next) {
            opt.carmen = next;
            ++i;
        } else if (strcmp(a, "--trajectory") == 0 && next) {
            opt.trajectory = next;
            ++i;
        } else if (strcmp(a, "--map") == 0 && next) {
            opt.map = next;
            ++i;
        } else if (strcmp(a, "--method") == 0 && next) {
            if (strcmp(next, "rsm") == 0) {
                cfg.method = RSM_METHOD_RSM;
            } else if (strcmp(next, "icp") == 0) {
                cfg.method = RSM_METHOD_ICP;
            } else if (strcmp(next, "odometry") == 0) {
                cfg.method = RSM_METHOD_ODOMETRY;
            } else {
                fprintf(stderr, "rsm-nav: unknown method '%s'\n", next);
                return 2;
            }
            ++i;
        } else if (strcmp(a, "--set") == 0 && next) {
            if (set_option(&cfg, next) != 0) {
                fprintf(stderr, "rsm-nav: bad --set '%s'\n", next);
                return 2;
            }
            ++i;
        } else if (strcmp(a, "--fov179") == 0) {
            reader.fov179 = 1;
        } else if (strcmp(a, "--quiet") == 0) {
            opt.quiet = 1;
        } else if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            return 0;
        } else {
            fprintf(stderr, "rsm-nav: unexpected argument '%s'\n", a);
            usage(stderr);
            return 2;
        }
    }
    if (opt.carmen == NULL || opt.trajectory == NULL) {
        usage(stderr);
        return 2;
    }
    if (carmen_open(&reader, opt.carmen) != 0) {
        fprintf(stderr, "rsm-nav: cannot open %s: %s\n", opt.carmen, strerror(errno));
        return 1;
    }
    traj = fopen(opt.trajectory, "w");
    if (traj == NULL) {
        fprintf(stderr, "rsm-nav: cannot write %s: %s\n", opt.trajectory, strerror(errno));
        carmen_close(&reader);
        return 1;
    }
    fprintf(traj, "# rsm-nav trajectory: timestamp[s] x[m] y[m] theta[rad]\n# source: %s\n", opt.carmen);
    t_start = now_s();
    for (;;) {
        const carmen_kind_t k = carmen_next(&reader, &rec);
        rsm_localizer_report_t rep;
        double t0;
        int rc;
        uint64_t us;
        size_t b;
        if (k == CARMEN_EOF) {
            break;
        }
        if (k != CARMEN_SCAN) {
            continue; /* odometry comes from the pose carried by each laser line */
        }
        if (!initialised) {
            /* Start in the odometry frame so the trajectories are comparable. */
            x0 = rec.odom;
            if (rsm_localizer_init(&loc, &cfg, &x0, NULL) != RSM_OK) {
                fprintf(stderr, "rsm-nav: invalid configuration\n");
                fclose(traj);
                carmen_close(&reader);
                return 2;
            }
            initialised = 1;
        }
        if (have_odom) {
            const rsm_motion_t u = rsm_odometry_from_poses(&last_odom, &rec.odom);
            (void)rsm_localizer_motion(&loc, &u);
        }
        last_odom = rec.odom;
        have_odom = 1;
        scan.count = rec.count;
        for (b = 0; b < rec.count; ++b) {
            scan.range_m[b] = rec.range_m[b];
        }
        (void)rsm_scan_set_uniform(&scan, rec.count, rec.start_rad, rec.step_rad);
        /* Log timestamps jitter backwards while the file order is the true
         * order (the Intel log does so 631 times): feed a clamped stamp and
         * count it; the trajectory keeps the original stamp. */
        us = (uint64_t)llround(rec.stamp_s * 1e6);
        if (us < last_us) {
            us = last_us;
            ++clamped;
        }
        last_us = us;
        scan.stamp_us = us;
        t0 = now_s();
        rc = rsm_localizer_scan(&loc, &scan, &rep);
        if (ntimes == cap_times) {
            cap_times = cap_times ? cap_times * 2 : 4096;
            times = (double *)realloc(times, cap_times * sizeof *times);
            if (times == NULL) {
                fprintf(stderr, "rsm-nav: out of memory\n");
                return 1;
            }
        }
        times[ntimes++] = now_s() - t0;
        if (rc != RSM_OK) {
            fprintf(stderr, "rsm-nav: scan at %.6f: %s\n", rec.stamp_s, rsm_strerror(rc));
            continue;
        }
        fprintf(traj, "%.6f %.6f %.6f %.6f\n", rec.stamp_s, (double)rep.pose.x, (double)rep.pose.y,
                (double)rep.pose.theta);
        if (opt.map != NULL) {
            (void)hitlist_add(&hits, loc.world, rep.points);
        }
        if (!opt.quiet && ntimes % 1000 == 0) {
            fprintf(stderr, "rsm-nav: %zu scans, %.1f s\n", ntimes, now_s() - t_start);
        }
    }
    if (fclose(traj) != 0) {
        fprintf(stderr, "rsm-nav: error writing %s\n", opt.trajectory);
        return 1;
    }
    carmen_close(&reader);
    if (opt.map != NULL && hits.count > 0) {
        if (pgm_write_map(opt.map, &hits, cfg.grid.cell_m) != 0) {
            fprintf(stderr, "rsm-nav: cannot write map %s\n", opt.map);
        }
    }
    hitlist_free(&hits);
    {
        const rsm_localizer_counters_t *c = &loc.counters;
        double median = 0.0;
        double p95 = 0.0;
        int o;
        if (ntimes > 0) {
            qsort(times, ntimes, sizeof *times, cmp_double);
            median = times[ntimes / 2];
            p95 = times[(ntimes * 95) / 100 < ntimes ? (ntimes * 95) / 100 : ntimes - 1];
        }
        printf("rsm-nav summary\n");
        printf("  method          %s\n", cfg.method == RSM_METHOD_RSM ? "rsm" : cfg.method == RSM_METHOD_ICP ? "icp" : "odometry");
        printf("  lines           %llu (scans %llu, odometry %llu, comments %llu, unknown %llu, malformed %llu, too many beams %llu, too long %llu)\n",
               (unsigned long long)reader.counts.lines, (unsigned long long)reader.counts.scans,
               (unsigned long long)reader.counts.odoms, (unsigned long long)reader.counts.comments,
               (unsigned long long)reader.counts.unknown, (unsigned long long)reader.counts.malformed,
               (unsigned long long)reader.counts.too_many_beams, (unsigned long long)reader.counts.too_long);
        printf("  timestamps      %llu clamped (went backwards in the log)\n", (unsigned long long)clamped);
        printf("  scans           %u\n", (unsigned)c->scans);
        for (o = 0; o < RSM_SCAN_OUTCOMES; ++o) {
            if (c->outcome[o] != 0) {
                printf("    %-14s %u\n", rsm_outcome_name((rsm_outcome_t)o), (unsigned)c->outcome[o]);
            }
        }
        printf("  readings dropped: nan %u, too short %u, too long %u\n", (unsigned)c->drops.nan,
               (unsigned)c->drops.too_short, (unsigned)c->drops.too_long);
        printf("  time per scan   median %.1f us, p95 %.1f us (this machine, wall clock)\n", median * 1e6, p95 * 1e6);
    }
    free(times);
    return 0;
}
