/* rsm-stages: measures one localizer step on a CARMEN log for ./tools/bench.
 *
 *   rsm-stages --carmen LOG [--method rsm|paper|icp] [--beams N] [--limit N] [--fov179]
 *              [--clock ns|none] [--trajectory OUT] [--stack]
 *
 * Runs the localizer over the log with rsm-nav's own loop (tools/nav/logrun.c:
 * same start pose, odometry increments from the poses of the laser lines,
 * the same repair of timestamps) and prints one JSON object: the build's
 * capacities and sizes, scan outcomes, the persistent map's use of its tile
 * pool (method rsm), and
 *   - with --clock ns (default): per-stage times from the localizer's timing
 *     hook (rsm_localizer_config_t.clock_fn reading CLOCK_MONOTONIC in ns),
 *     the whole call timed from outside, and rsm_localizer_motion; median,
 *     95th percentile, mean and maximum over the scans, in microseconds;
 *   - with --stack: the stack high-water mark of rsm_localizer_scan, by
 *     painting. Each scan runs in a fresh thread whose stack (a buffer of
 *     this program) was filled with a pattern; after the thread ends, the
 *     lowest byte no longer holding the pattern gives the depth the thread
 *     reached. A thread that calls an empty function with the same arguments
 *     gives the baseline (thread start-up, TLS, the call itself); the
 *     difference is the stack of one rsm_localizer_scan call, maximum over
 *     the scans. Not available under AddressSanitizer (it moves frames off
 *     the stack).
 * --beams N resamples every scan to N readings over the same field of view:
 * linear in range between two neighbouring usable readings less than 0.1 m
 * apart, otherwise the nearer reading (so no point is invented between an
 * edge and the background). It adds readings, not information.
 * --trajectory writes rsm-nav's trajectory format (one line per scan).
 * The CARMEN reader is rsm-nav's (tools/nav/carmen.c, compiled in). */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "carmen.h"
#include "logrun.h"
#include "rsm/localizer.h"
#include "rsm/status.h"
#include "map/tilemap.h" /* internal (src/): tiles held per level */

#if defined(__SANITIZE_ADDRESS__)
#define STAGES_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define STAGES_ASAN 1
#endif
#endif
#ifndef STAGES_ASAN
#define STAGES_ASAN 0
#endif

#if defined(__GNUC__)
#define STAGES_NOINLINE __attribute__((noinline))
#else
#define STAGES_NOINLINE
#endif

#define STACK_BYTES (256u * 1024u)
#define STACK_PATTERN 0xA5u
#define RESAMPLE_JUMP_M 0.1f

typedef struct options {
    const char *carmen;
    const char *trajectory;
    rsm_method_t method;
    size_t beams;      /* 0: as in the log */
    size_t limit;      /* 0: every scan */
    int fov179;
    int clock_ns;
    int stack;
} options_t;

/* Growing arrays of per-scan samples (host tool: the heap is fine here). */
typedef struct samples {
    double *v;
    size_t n;
    size_t cap;
} samples_t;

typedef struct stack_probe {
    unsigned char *buf;         /* the threads' stack */
    size_t size;
    size_t peak;                /* deepest use seen with rsm_localizer_scan */
    size_t baseline;            /* deepest use of the empty call */
    size_t measured;            /* scans measured */
} stack_probe_t;

typedef struct run {
    options_t opt;
    rsm_localizer_t loc;
    rsm_localizer_config_t cfg;
    carmen_reader_t reader;
    carmen_record_t rec;
    rsm_scan_t scan;
    int initialised;
    stamp_repair_t repair;
    size_t scans;
    size_t beams_in;
    size_t beams_out;
    samples_t stage[RSM_STAGE_COUNT];
    samples_t step;
    samples_t call;
    samples_t motion;
    FILE *traj;
    stack_probe_t probe;
} run_t;

static run_t g_run; /* one run per process; too big for a thread's stack */

static void die(const char *msg)
{
    fprintf(stderr, "rsm-stages: %s\n", msg);
    exit(2);
}

static void push(samples_t *s, double v)
{
    if (s->n == s->cap) {
        size_t cap = s->cap ? s->cap * 2u : 16384u;
        double *nv = (double *)realloc(s->v, cap * sizeof *nv);
        if (nv == NULL) {
            die("out of memory");
        }
        s->v = nv;
        s->cap = cap;
    }
    s->v[s->n++] = v;
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a;
    const double y = *(const double *)b;
    return (x > y) - (x < y);
}

static uint64_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

/* The timing hook: nanoseconds, modulo 2^32 (a wrap every 4.3 s; one scan
 * takes far less). */
static uint32_t hook_clock_ns(void *ctx)
{
    (void)ctx;
    return (uint32_t)now_ns();
}

/* ---- resampling -------------------------------------------------------------- */

static int usable(float r, const rsm_scan_limits_t *lim)
{
    return isfinite(r) && r > lim->min_range_m && r < lim->max_range_m;
}

/* Fills scan with n readings spread over the record's field of view. */
static void resample(const carmen_record_t *rec, size_t n, const rsm_scan_limits_t *lim, rsm_scan_t *scan)
{
    const size_t m = rec->count;
    const float span = rec->step_rad * (float)(m - 1u);
    const float step = span / (float)(n - 1u);
    size_t k;
    for (k = 0; k < n; ++k) {
        const float u = (float)k * (float)(m - 1u) / (float)(n - 1u);
        size_t i0 = (size_t)u;
        float f;
        float r0;
        float r1;
        if (i0 >= m - 1u) {
            i0 = m - 2u;
        }
        f = u - (float)i0;
        r0 = rec->range_m[i0];
        r1 = rec->range_m[i0 + 1u];
        if (usable(r0, lim) && usable(r1, lim) && fabsf(r0 - r1) < RESAMPLE_JUMP_M) {
            scan->range_m[k] = r0 + f * (r1 - r0);
        } else {
            scan->range_m[k] = f < 0.5f ? r0 : r1;
        }
    }
    (void)rsm_scan_set_uniform(scan, n, rec->start_rad, step);
}

/* ---- stack painting ------------------------------------------------------------- */

typedef struct scan_call {
    rsm_localizer_t *loc;
    const rsm_scan_t *scan;
    rsm_localizer_report_t *rep;
    int rc;
    int empty;
} scan_call_t;

static STAGES_NOINLINE int empty_scan(rsm_localizer_t *loc, const rsm_scan_t *scan, rsm_localizer_report_t *rep)
{
    /* Same signature as rsm_localizer_scan; touches nothing. */
    return loc != NULL && scan != NULL && rep != NULL ? RSM_OK : RSM_ERR_INVAL;
}

static void *scan_thread(void *arg)
{
    scan_call_t *c = (scan_call_t *)arg;
    c->rc = c->empty ? empty_scan(c->loc, c->scan, c->rep) : rsm_localizer_scan(c->loc, c->scan, c->rep);
    return NULL;
}

/* Depth the last thread reached: from the top of the buffer down to the
 * lowest byte that lost the pattern. Repaints what was used. */
static size_t stack_used_and_repaint(stack_probe_t *p)
{
    size_t i = 0;
    size_t used;
    while (i < p->size && p->buf[i] == (unsigned char)STACK_PATTERN) {
        ++i;
    }
    used = p->size - i;
    memset(p->buf + i, STACK_PATTERN, used);
    return used;
}

static int call_in_thread(stack_probe_t *p, scan_call_t *c, size_t *used)
{
    pthread_attr_t attr;
    pthread_t th;
    int rc = pthread_attr_init(&attr);
    if (rc == 0) {
        rc = pthread_attr_setstack(&attr, p->buf, p->size);
    }
    if (rc == 0) {
        rc = pthread_create(&th, &attr, scan_thread, c);
    }
    if (rc == 0) {
        rc = pthread_join(th, NULL);
    }
    (void)pthread_attr_destroy(&attr);
    if (rc != 0) {
        return rc;
    }
    *used = stack_used_and_repaint(p);
    if (*used >= p->size) {
        die("the stack probe's buffer was used up: enlarge STACK_BYTES");
    }
    return 0;
}

static int painted_scan(run_t *r, rsm_localizer_report_t *rep)
{
    scan_call_t c;
    size_t used = 0;
    c.loc = &r->loc;
    c.scan = &r->scan;
    c.rep = rep;
    c.rc = RSM_ERR_INVAL;
    c.empty = 1;
    if (call_in_thread(&r->probe, &c, &used) != 0) {
        die("cannot run a thread on the painted stack");
    }
    if (used > r->probe.baseline) {
        r->probe.baseline = used;
    }
    c.empty = 0;
    if (call_in_thread(&r->probe, &c, &used) != 0) {
        die("cannot run a thread on the painted stack");
    }
    if (used > r->probe.peak) {
        r->probe.peak = used;
    }
    r->probe.measured++;
    return c.rc;
}

/* ---- the run ----------------------------------------------------------------------- */

/* logrun ops: the first scan record starts the localizer at its pose. */
static int start_cb(void *ctx, const carmen_record_t *rec)
{
    run_t *r = (run_t *)ctx;
    if (rsm_localizer_init(&r->loc, &r->cfg, &rec->odom, NULL) != RSM_OK) {
        const char *field = "none (the start pose is out of range)";
        (void)rsm_localizer_config_check(&r->cfg, &field);
        fprintf(stderr, "rsm-stages: invalid configuration: the localizer refuses its field %s\n", field);
        return -1;
    }
    r->initialised = 1;
    r->beams_in = rec->count;
    return 0;
}

/* Resampling needs two readings to span the field of view. */
static int want_cb(void *ctx, const carmen_record_t *rec)
{
    const run_t *r = (const run_t *)ctx;
    return r->opt.beams == 0u || rec->count >= 2u;
}

static void motion_cb(void *ctx, const rsm_motion_t *u)
{
    run_t *r = (run_t *)ctx;
    const uint64_t t0 = now_ns();
    (void)rsm_localizer_motion(&r->loc, u);
    if (!r->opt.stack) {
        push(&r->motion, (double)(now_ns() - t0) * 1e-3);
    }
}

static void scan_cb(void *ctx, const carmen_record_t *rec, uint64_t stamp_us)
{
    run_t *r = (run_t *)ctx;
    rsm_localizer_report_t rep;
    uint64_t t0;
    uint64_t t1;
    int rc;
    size_t s;
    if (r->opt.beams > 0u) {
        resample(rec, r->opt.beams, &r->cfg.limits, &r->scan);
    } else {
        logrun_scan(rec, &r->scan);
    }
    r->beams_out = r->scan.count;
    r->scan.stamp_us = stamp_us;
    if (r->opt.stack) {
        rc = painted_scan(r, &rep);
    } else {
        t0 = now_ns();
        rc = rsm_localizer_scan(&r->loc, &r->scan, &rep);
        t1 = now_ns();
        push(&r->call, (double)(t1 - t0) * 1e-3);
        if (r->opt.clock_ns) {
            for (s = 0; s < RSM_STAGE_COUNT; ++s) {
                push(&r->stage[s], (double)rep.stage_time[s] * 1e-3);
            }
            push(&r->step, (double)rep.step_time * 1e-3);
        }
    }
    r->scans++;
    if (rc != RSM_OK) {
        fprintf(stderr, "rsm-stages: scan at %.6f: %s\n", rec->stamp_s, rsm_strerror(rc));
        return;
    }
    if (r->traj != NULL) {
        fprintf(r->traj, "%.6f %.6f %.6f %.6f\n", rec->stamp_s, (double)rep.pose.x, (double)rep.pose.y,
                (double)rep.pose.theta);
    }
}

static int done_cb(void *ctx)
{
    const run_t *r = (const run_t *)ctx;
    return r->opt.limit > 0u && r->scans >= r->opt.limit;
}

static int run_log(run_t *r)
{
    static const logrun_ops_t ops = {start_cb, want_cb, motion_cb, scan_cb, done_cb};
    int rc;
    r->reader.fov179 = r->opt.fov179;
    rc = logrun_carmen(&r->reader, &r->rec, r->opt.carmen, "rsm-stages", &r->repair, &ops, r, 0);
    return rc < 0 ? 1 : rc;
}

/* ---- output ----------------------------------------------------------------------- */

static void print_stats(const char *name, samples_t *s, int last)
{
    double sum = 0.0;
    size_t reached = 0;
    size_t i;
    double *nz;
    size_t nnz = 0;
    if (s->n == 0) {
        printf("    \"%s\": null%s\n", name, last ? "" : ",");
        return;
    }
    nz = (double *)malloc(s->n * sizeof *nz);
    if (nz == NULL) {
        die("out of memory");
    }
    for (i = 0; i < s->n; ++i) {
        sum += s->v[i];
        if (s->v[i] > 0.0) {
            nz[nnz++] = s->v[i];
            ++reached;
        }
    }
    qsort(s->v, s->n, sizeof *s->v, cmp_double);
    qsort(nz, nnz, sizeof *nz, cmp_double);
    /* Percentiles as rsm-nav takes them: element n/2 and n*95/100 of the sorted samples. */
    printf("    \"%s\": {\"n\": %zu, \"reached\": %zu, \"mean_us\": %.4f, \"median_us\": %.4f, \"p95_us\": %.4f, "
           "\"max_us\": %.4f, \"median_reached_us\": %.4f, \"p95_reached_us\": %.4f}%s\n",
           name, s->n, reached, sum / (double)s->n, s->v[s->n / 2u], s->v[(s->n * 95u) / 100u], s->v[s->n - 1u],
           nnz ? nz[nnz / 2u] : 0.0, nnz ? nz[(nnz * 95u) / 100u] : 0.0, last ? "" : ",");
    free(nz);
}

#define LOC_PART(name, expr) printf("    \"%s\": %lu,\n", name, (unsigned long)(expr))

static void print_json(run_t *r)
{
    const rsm_localizer_t *loc = &r->loc;
    size_t s;
    printf("{\n  \"tool\": \"rsm-stages\",\n");
    printf("  \"method\": \"%s\",\n",
           r->cfg.method == RSM_METHOD_ICP ? "icp" : r->cfg.method == RSM_METHOD_PAPER ? "paper" : "rsm");
    printf("  \"scans\": %zu,\n  \"beams_in\": %zu,\n  \"beams\": %zu,\n  \"clamped\": %llu,\n", r->scans, r->beams_in,
           r->beams_out, (unsigned long long)r->repair.clamped);
    printf("  \"config\": {\"RSM_MAX_BEAMS\": %d, \"RSM_MAP_SIZE_LOG2\": %d, \"RSM_MAP_SIZE\": %d, "
           "\"RSM_IMAGE_MAX_CELLS\": %d, \"RSM_MAX_KEYPOINTS\": %d, \"RSM_MAX_CANDIDATES\": %d, "
           "\"RSM_MAX_MATCHES\": %d, \"RSM_ICP_MAX_POINTS\": %d, \"RSM_TMAP_TILES\": %d, "
           "\"RSM_TMAP_LEVELS\": %d, \"RSM_TMAP_TILE_LOG2\": %d, \"RSM_TMAP_HASH_LOG2\": %d, \"cell_m\": %.6f, "
           "\"tmap_cell_m\": %.6f},\n",
           (int)RSM_MAX_BEAMS, (int)RSM_MAP_SIZE_LOG2, (int)RSM_MAP_SIZE, (int)RSM_IMAGE_MAX_CELLS,
           (int)RSM_MAX_KEYPOINTS, (int)RSM_MAX_CANDIDATES, (int)RSM_MAX_MATCHES, (int)RSM_ICP_MAX_POINTS,
           (int)RSM_TMAP_TILES, (int)RSM_TMAP_LEVELS, (int)RSM_TMAP_TILE_LOG2, (int)RSM_TMAP_HASH_LOG2,
           (double)r->cfg.grid.cell_m, (double)r->cfg.tmap.cell_m);
    printf("  \"sizes\": {\n");
    LOC_PART("rsm_localizer_t", sizeof *loc);
    LOC_PART("ekf", sizeof loc->ekf);
    LOC_PART("odo", sizeof loc->odo);
    LOC_PART("state", sizeof loc->state);
    LOC_PART("state.persistent", sizeof loc->state.persistent);
    LOC_PART("state.persistent.map", sizeof loc->state.persistent.map);
    LOC_PART("state.persistent.map.tile", sizeof loc->state.persistent.map.tile);
    LOC_PART("state.persistent.map.hash", sizeof loc->state.persistent.map.hash);
    LOC_PART("state.paper", sizeof loc->state.paper);
    LOC_PART("state.paper.map", sizeof loc->state.paper.map);
    LOC_PART("state.paper.image", sizeof loc->state.paper.image);
    LOC_PART("state.paper.ransac", sizeof loc->state.paper.ransac);
    LOC_PART("state.paper.harris", sizeof loc->state.paper.visited + sizeof loc->state.paper.harris +
                                       sizeof loc->state.paper.cands);
    LOC_PART("state.paper.keypoints", sizeof loc->state.paper.kp_cur + sizeof loc->state.paper.kp_ref +
                                          sizeof loc->state.paper.pt_cur + sizeof loc->state.paper.pt_ref);
    LOC_PART("state.paper.matches", sizeof loc->state.paper.matches);
    LOC_PART("state.icp", sizeof loc->state.icp);
    LOC_PART("points", sizeof loc->pts + sizeof loc->frame.world);
    LOC_PART("counters", sizeof loc->counters);
    LOC_PART("last", sizeof loc->last);
    LOC_PART("rsm_scan_t", sizeof(rsm_scan_t));
    printf("    \"rsm_localizer_config_t\": %lu\n  },\n", (unsigned long)sizeof(rsm_localizer_config_t));
    printf("  \"outcomes\": {");
    for (s = 0; s < RSM_SCAN_OUTCOMES; ++s) {
        printf("\"%s\": %lu%s", rsm_outcome_name((rsm_outcome_t)s), (unsigned long)loc->counters.outcome[s],
               s + 1u < RSM_SCAN_OUTCOMES ? ", " : "");
    }
    printf("},\n");
    if (r->cfg.method == RSM_METHOD_MAP && r->initialised) {
        /* How much of the tile pool the log used: the margin of a capacity. */
        const rsm_tmap_t *m = &loc->state.persistent.map;
        uint32_t l;
        printf("  \"tmap\": {\"tiles\": [");
        for (l = 0; l < (uint32_t)RSM_TMAP_LEVELS; ++l) {
            printf("%u%s", (unsigned)rsm_tmap_tiles(m, l), l + 1u < (uint32_t)RSM_TMAP_LEVELS ? ", " : "");
        }
        printf("], \"used\": %u, \"updates\": %u, \"allocated\": %u, \"evicted\": %u, \"dropped\": %u, "
               "\"searches\": %u, \"recovered\": %u},\n",
               (unsigned)m->used, (unsigned)m->counters.updates, (unsigned)m->counters.allocated,
               (unsigned)m->counters.evicted, (unsigned)m->counters.dropped, (unsigned)loc->counters.searches,
               (unsigned)loc->counters.recovered);
    } else {
        printf("  \"tmap\": null,\n");
    }
    if (r->opt.stack) {
        printf("  \"stack\": {\"buffer_bytes\": %zu, \"scans\": %zu, \"peak_bytes\": %zu, \"baseline_bytes\": %zu, "
               "\"scan_bytes\": %zu},\n",
               r->probe.size, r->probe.measured, r->probe.peak, r->probe.baseline,
               r->probe.peak > r->probe.baseline ? r->probe.peak - r->probe.baseline : (size_t)0);
    } else {
        printf("  \"stack\": null,\n");
    }
    printf("  \"clock\": \"%s\",\n", r->opt.stack ? "none (stack run)" : r->opt.clock_ns ? "CLOCK_MONOTONIC ns" : "none");
    printf("  \"timing\": {\n");
    for (s = 0; s < RSM_STAGE_COUNT; ++s) {
        print_stats(rsm_stage_name((rsm_stage_t)s), &r->stage[s], 0);
    }
    print_stats("step", &r->step, 0);
    print_stats("call", &r->call, 0);
    print_stats("motion", &r->motion, 1);
    printf("  }\n}\n");
}

static void usage(FILE *f)
{
    fprintf(f, "usage: rsm-stages --carmen LOG [--method rsm|paper|icp] [--beams N] [--limit N] [--fov179]\n"
               "                  [--clock ns|none] [--trajectory OUT] [--stack]\n");
}

static size_t parse_count(const char *s, size_t lo, size_t hi)
{
    char *end;
    unsigned long v;
    errno = 0;
    v = strtoul(s, &end, 10);
    if (*end != '\0' || end == s || errno != 0 || v < lo || v > hi) {
        usage(stderr);
        die("bad number");
    }
    return (size_t)v;
}

enum { OPT_CARMEN = 256, OPT_TRAJECTORY, OPT_METHOD, OPT_BEAMS, OPT_LIMIT, OPT_CLOCK, OPT_FOV179, OPT_STACK };

static const struct option stages_options[] = {
    {"carmen", required_argument, NULL, OPT_CARMEN},
    {"trajectory", required_argument, NULL, OPT_TRAJECTORY},
    {"method", required_argument, NULL, OPT_METHOD},
    {"beams", required_argument, NULL, OPT_BEAMS},
    {"limit", required_argument, NULL, OPT_LIMIT},
    {"clock", required_argument, NULL, OPT_CLOCK},
    {"fov179", no_argument, NULL, OPT_FOV179},
    {"stack", no_argument, NULL, OPT_STACK},
    {"help", no_argument, NULL, 'h'},
    {NULL, 0, NULL, 0}
};

int main(int argc, char **argv)
{
    run_t *r = &g_run;
    int opt;
    int rc;
    r->opt.method = RSM_METHOD_MAP;
    r->opt.clock_ns = 1;
    opterr = 0; /* every bad argument gets the usage */
    while ((opt = getopt_long(argc, argv, "+:h", stages_options, NULL)) != -1) {
        switch (opt) {
        case OPT_CARMEN:
            r->opt.carmen = optarg;
            break;
        case OPT_TRAJECTORY:
            r->opt.trajectory = optarg;
            break;
        case OPT_METHOD:
            if (strcmp(optarg, "rsm") == 0) {
                r->opt.method = RSM_METHOD_MAP;
            } else if (strcmp(optarg, "paper") == 0) {
                r->opt.method = RSM_METHOD_PAPER;
            } else if (strcmp(optarg, "icp") == 0) {
                r->opt.method = RSM_METHOD_ICP;
            } else {
                usage(stderr);
                return 2;
            }
            break;
        case OPT_BEAMS:
            r->opt.beams = parse_count(optarg, 2u, (size_t)RSM_MAX_BEAMS);
            break;
        case OPT_LIMIT:
            r->opt.limit = parse_count(optarg, 1u, (size_t)-1);
            break;
        case OPT_CLOCK:
            if (strcmp(optarg, "ns") == 0) {
                r->opt.clock_ns = 1;
            } else if (strcmp(optarg, "none") == 0) {
                r->opt.clock_ns = 0;
            } else {
                usage(stderr);
                return 2;
            }
            break;
        case OPT_FOV179:
            r->opt.fov179 = 1;
            break;
        case OPT_STACK:
            r->opt.stack = 1;
            break;
        case 'h':
            usage(stdout);
            return 0;
        default: /* unknown option, or a value missing */
            usage(stderr);
            return 2;
        }
    }
    if (optind < argc) {
        usage(stderr);
        return 2;
    }
    if (r->opt.carmen == NULL) {
        usage(stderr);
        return 2;
    }
    if (r->opt.stack && STAGES_ASAN) {
        die("--stack cannot measure under AddressSanitizer (frames live off the stack)");
    }
    r->cfg = rsm_localizer_config_default();
    r->cfg.method = r->opt.method;
    if (r->opt.clock_ns && !r->opt.stack) {
        r->cfg.clock_fn = hook_clock_ns;
        r->cfg.clock_ctx = NULL;
    }
    if (r->opt.stack) {
        void *buf = NULL;
        r->probe.size = STACK_BYTES;
        if (posix_memalign(&buf, 4096u, r->probe.size) != 0) {
            die("out of memory");
        }
        r->probe.buf = (unsigned char *)buf;
        memset(r->probe.buf, STACK_PATTERN, r->probe.size);
    }
    if (r->opt.trajectory != NULL) {
        r->traj = fopen(r->opt.trajectory, "w");
        if (r->traj == NULL) {
            fprintf(stderr, "rsm-stages: cannot write %s: %s\n", r->opt.trajectory, strerror(errno));
            return 1;
        }
        fprintf(r->traj, "# rsm-stages trajectory: timestamp[s] x[m] y[m] theta[rad]\n# source: %s\n",
                r->opt.carmen);
    }
    rc = run_log(r);
    if (r->traj != NULL && fclose(r->traj) != 0) {
        fprintf(stderr, "rsm-stages: cannot write %s\n", r->opt.trajectory);
        rc = rc ? rc : 1;
    }
    if (rc == 0) {
        if (r->scans == 0) {
            fprintf(stderr, "rsm-stages: no scan in %s\n", r->opt.carmen);
            return 1;
        }
        print_json(r);
    }
    return rc;
}
