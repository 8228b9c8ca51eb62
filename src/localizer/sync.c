#include "rsm/sync.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "rsm/odometry.h"
#include "rsm/status.h"
#include "core/burst.h"
#include "core/check.h"

typedef enum fuse_class {
    FUSE_ON_TIME = 0, /* interpolated or exact, decided in fuse() */
    FUSE_LATE,
    FUSE_TIMED_OUT,
    FUSE_SUPERSEDED
} fuse_class_t;

rsm_sync_config_t rsm_sync_config_default(void)
{
    rsm_sync_config_t c;
    c.max_wait_us = 250000u;
    c.hold_us = 500000u;
    c.scan_offset_us = 0;
    c.snap_us = 1000u;
    c.max_travel_m = 2.0f;
    return c;
}

/* from + (to - from) * num / den, rounded to nearest; den > 0, num <= den.
 * |diff| <= 2^31 and num < 2^32 keep the product inside int64. The result
 * is not masked: every reader of the counts takes differences modulo the
 * counter width (rsm_odometry_count_delta). */
static uint32_t counter_lerp(uint8_t bits, uint32_t from, uint32_t to, uint64_t num, uint64_t den)
{
    const int64_t d = rsm_odometry_count_delta(to, from, bits);
    const int64_t p = d * (int64_t)num;
    const int64_t half = (int64_t)(den / 2u);
    const int64_t part = p >= 0 ? (p + half) / (int64_t)den : -((-p + half) / (int64_t)den);
    return (uint32_t)((int64_t)from + part);
}

/* The increments composed since the last prediction, as one prediction. */
static void predict(rsm_sync_t *s)
{
    static const rsm_pose_t none = {0.0f, 0.0f, 0.0f};
    if (s->have_pending) {
        const rsm_motion_t u = {s->pending.x, s->pending.y, s->pending.theta};
        (void)rsm_localizer_motion(s->loc, &u);
    }
    s->pending = none;
    s->pending_travel_m = 0.0f;
    s->pending_turn_rad = 0.0f;
    s->have_pending = 0u;
}

static void apply(rsm_sync_t *s, const rsm_odometry_sample_t *smp)
{
    rsm_motion_t u;
    /* The first sample only latches the counters (RSM_ERR_AGAIN); an
     * implausible step is refused and counted by the odometry, which gets
     * the sample's time so that the allowance grows with the gap. */
    if (rsm_odometry_update_ticks_at(&s->loc->odo, smp->left, smp->right, smp->stamp_us, &u) == RSM_OK) {
        /* Wheel travel: the chord, or half the base times the turn when
         * turning on the spot ((|dl| + |dr|) / 2 within the chord's error). */
        const float chord = sqrtf(u.dx * u.dx + u.dy * u.dy);
        const float turn = 0.5f * s->loc->odo.cfg.wheel_base_m * fabsf(u.dtheta);
        if (s->have_pending && fabsf(s->pending_turn_rad + u.dtheta) >= RSM_PI) {
            /* The composed heading is wrapped: a turn past a half one would
             * come out as a smaller one the other way, with its noise. */
            s->counters.blind_predictions++;
            predict(s);
        }
        s->pending = rsm_odometry_apply(&s->pending, &u);
        s->pending_travel_m += chord > turn ? chord : turn;
        s->pending_turn_rad += u.dtheta;
        s->have_pending = 1u;
        if (s->pending_travel_m >= s->cfg->max_travel_m) {
            if (s->cfg->max_travel_m > 0.0f) {
                s->counters.blind_predictions++;
            }
            predict(s);
        }
    }
    s->base = *smp;
    s->have_base = 1u;
}

static const rsm_odometry_sample_t *front(const rsm_sync_t *s)
{
    return s->count > 0u ? &s->ring[s->head] : NULL;
}

static const rsm_odometry_sample_t *newest(const rsm_sync_t *s)
{
    if (s->count > 0u) {
        return &s->ring[(s->head + s->count - 1u) % RSM_SYNC_DEPTH];
    }
    return s->have_base ? &s->base : NULL;
}

static void apply_front(rsm_sync_t *s)
{
    const rsm_odometry_sample_t smp = s->ring[s->head];
    s->head = (s->head + 1u) % RSM_SYNC_DEPTH;
    s->count--;
    apply(s, &smp);
}

/* The scan's stamp plus the offset, saturated at both ends (unsigned
 * arithmetic: a stamp near 2^63 or 2^64 must not overflow). */
static uint64_t scan_time(const rsm_sync_t *s, const rsm_scan_t *scan)
{
    const int32_t off = s->cfg->scan_offset_us;
    if (off < 0) {
        const uint64_t back = (uint64_t)(-(int64_t)off);
        return scan->stamp_us < back ? 0u : scan->stamp_us - back;
    }
    return scan->stamp_us > UINT64_MAX - (uint64_t)off ? UINT64_MAX : scan->stamp_us + (uint64_t)off;
}

/* Brings the odometry up to time t and runs the scan. */
static void fuse(rsm_sync_t *s, const rsm_scan_t *scan, uint64_t t, fuse_class_t cls)
{
    rsm_localizer_report_t rep;
    const rsm_odometry_sample_t *next;
    int rc;
    while ((next = front(s)) != NULL && next->stamp_us <= t) {
        apply_front(s);
    }
    if (cls == FUSE_ON_TIME) {
        /* A sample within snap_us of t (before it, or else just after it)
         * counts as taken with the scan: the two links' arrival jitter. */
        const uint32_t snap = s->cfg->snap_us;
        if (next == NULL || (s->have_base && t - s->base.stamp_us <= snap)) {
            s->counters.exact++;
        } else if (next->stamp_us - t <= snap || !s->have_base) {
            apply_front(s);
            s->counters.exact++;
        } else {
            /* next is past t: split the step between base and next at t. */
            const uint8_t bits = s->loc->odo.cfg.counter_bits;
            const uint64_t den = next->stamp_us - s->base.stamp_us;
            const uint64_t num = t - s->base.stamp_us;
            rsm_odometry_sample_t mid;
            if (den > 0xFFFFFFFFu) {
                mid = s->base; /* over an hour between samples: nothing to interpolate */
            } else {
                mid.stamp_us = t;
                mid.left = counter_lerp(bits, s->base.left, next->left, num, den);
                mid.right = counter_lerp(bits, s->base.right, next->right, num, den);
            }
            apply(s, &mid);
            s->counters.interpolated++;
        }
    } else if (cls == FUSE_LATE) {
        s->counters.late++;
    } else if (cls == FUSE_TIMED_OUT) {
        s->counters.timed_out++;
    } else {
        s->counters.superseded++;
    }
    predict(s);
    rc = rsm_localizer_scan(s->loc, scan, &rep);
    if (s->on_result != NULL) {
        s->on_result(s->ctx, scan, rc, &rep);
    }
}

/* Whether rsm_sync_init set s up (not for NULL, zeroed or stale memory). */
static int ready(const rsm_sync_t *s)
{
    return s != NULL && s->magic == (uint32_t)RSM_SYNC_MAGIC && s->loc != NULL && s->cfg != NULL;
}

static void fuse_held(rsm_sync_t *s, fuse_class_t cls)
{
    s->holding = 0u;
    fuse(s, &s->held, s->held_since_us, cls);
}

int rsm_sync_init_checked(rsm_sync_t *s, size_t s_size, unsigned long fingerprint, rsm_localizer_t *loc,
                          const rsm_sync_config_t *cfg, rsm_sync_result_fn on_result, void *ctx)
{
    if (!RSM_SAME_BUILD(rsm_sync_t, s_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    /* The localizer's own mark, not just a config pointer: stale memory
     * has one. */
    if (s == NULL || loc == NULL || loc->magic != (uint32_t)RSM_LOCALIZER_MAGIC || loc->cfg == NULL ||
        cfg == NULL) {
        return RSM_ERR_INVAL;
    }
    if (cfg->max_wait_us == 0u && cfg->hold_us == 0u) {
        /* Both zero would still work, but means "no alignment": say so. */
        return RSM_ERR_INVAL;
    }
    if (!(cfg->max_travel_m >= 0.0f && cfg->max_travel_m <= 1e6f)) { /* NaN fails too */
        return RSM_ERR_INVAL;
    }
    memset(s, 0, sizeof *s);
    s->magic = (uint32_t)RSM_SYNC_MAGIC;
    s->loc = loc;
    s->cfg = cfg;
    s->on_result = on_result;
    s->ctx = ctx;
    return RSM_OK;
}

int rsm_sync_encoder(rsm_sync_t *s, const rsm_odometry_sample_t *sample)
{
    const rsm_odometry_sample_t *last;
    rsm_odometry_sample_t smp;
    uint64_t stamp_us;
    if (!ready(s) || sample == NULL) {
        return RSM_ERR_INVAL;
    }
    s->counters.encoders++;
    smp = *sample;
    last = newest(s);
    if (last != NULL && smp.stamp_us < last->stamp_us) {
        /* Arrival order is the true order of one link's packets. */
        smp.stamp_us = last->stamp_us;
        s->counters.encoder_backwards++;
    }
    stamp_us = smp.stamp_us;
    if (s->count > 0u && (s->count >= 2u || s->have_base)) {
        /* A burst (core/burst.h): the newest is put halfway between the
         * one before and this one; its counts are kept. */
        rsm_odometry_sample_t *nw = &s->ring[(s->head + s->count - 1u) % RSM_SYNC_DEPTH];
        const uint64_t before = s->count >= 2u ? s->ring[(s->head + s->count - 2u) % RSM_SYNC_DEPTH].stamp_us
                                               : s->base.stamp_us;
        if (rsm_burst_restamp(before, &nw->stamp_us, stamp_us)) {
            s->counters.encoder_bursts++;
        }
    }
    if (s->count == RSM_SYNC_DEPTH) {
        apply_front(s);
        s->counters.encoder_overflow++;
    }
    s->ring[(s->head + s->count) % RSM_SYNC_DEPTH] = smp;
    s->count++;
    if (s->holding) {
        if (stamp_us + s->cfg->snap_us >= s->held_since_us) {
            fuse_held(s, FUSE_ON_TIME);
        } else {
            apply_front(s); /* before the waiting scan: apply it now */
        }
    }
    while (s->count > 0u && s->ring[s->head].stamp_us + s->cfg->hold_us < stamp_us) {
        apply_front(s);
    }
    return RSM_OK;
}

int rsm_sync_encoder_restart(rsm_sync_t *s)
{
    if (!ready(s)) {
        return RSM_ERR_INVAL;
    }
    while (s->count > 0u) {
        apply_front(s);
    }
    s->have_base = 0u;
    rsm_odometry_restart(&s->loc->odo);
    s->counters.restarts++;
    return RSM_OK;
}

int rsm_sync_scan_checked(rsm_sync_t *s, const rsm_scan_t *scan, size_t scan_size, unsigned long fingerprint)
{
    const rsm_odometry_sample_t *last;
    uint64_t t;
    if (!RSM_SAME_BUILD(rsm_scan_t, scan_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (!ready(s) || scan == NULL) {
        return RSM_ERR_INVAL;
    }
    s->counters.scans++;
    if (scan->count > RSM_MAX_BEAMS) {
        return RSM_ERR_INVAL;
    }
    if (s->holding) {
        fuse_held(s, FUSE_SUPERSEDED);
    }
    t = scan_time(s, scan);
    last = newest(s);
    if (last == NULL || last->stamp_us + s->cfg->snap_us >= t) {
        /* No odometry at all, or some at or past the scan's time. */
        fuse(s, scan, t, (s->have_base && t < s->base.stamp_us) ? FUSE_LATE : FUSE_ON_TIME);
        return RSM_OK;
    }
    /* Every held sample predates the scan: apply them and wait for one past it. */
    while (s->count > 0u) {
        apply_front(s);
    }
    s->held = *scan;
    s->held_since_us = t;
    s->holding = 1u;
    return RSM_OK;
}

int rsm_sync_poll(rsm_sync_t *s, uint64_t now_us)
{
    if (!ready(s)) {
        return RSM_ERR_INVAL;
    }
    if (s->holding && now_us >= s->held_since_us && now_us - s->held_since_us >= s->cfg->max_wait_us) {
        fuse_held(s, FUSE_TIMED_OUT);
        return 1;
    }
    return 0;
}

int rsm_sync_flush(rsm_sync_t *s)
{
    int fused = 0;
    if (!ready(s)) {
        return RSM_ERR_INVAL;
    }
    if (s->holding) {
        fuse_held(s, FUSE_TIMED_OUT);
        fused = 1;
    }
    while (s->count > 0u) {
        apply_front(s);
    }
    predict(s);
    return fused;
}

rsm_pose_t rsm_sync_pose(const rsm_sync_t *s)
{
    rsm_pose_t est;
    rsm_pose_t pose;
    const rsm_odometry_sample_t *from;
    const rsm_odometry_sample_t *to;
    if (!ready(s)) {
        const rsm_pose_t none = {NAN, NAN, NAN};
        return none;
    }
    est = rsm_localizer_pose(s->loc);
    pose = rsm_pose_compose(&est, &s->pending);
    from = s->have_base ? &s->base : front(s);
    to = newest(s);
    if (from != NULL && to != NULL && from != to) {
        const uint8_t bits = s->loc->odo.cfg.counter_bits;
        const int32_t dl = rsm_odometry_count_delta(to->left, from->left, bits);
        const int32_t dr = rsm_odometry_count_delta(to->right, from->right, bits);
        const rsm_motion_t u = rsm_odometry_from_ticks(&s->loc->odo.cfg, dl, dr);
        pose = rsm_odometry_apply(&pose, &u);
    }
    return pose;
}
