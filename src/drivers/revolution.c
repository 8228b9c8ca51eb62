#include "rsm/revolution.h"

#include <math.h>
#include <string.h>

#include "rsm/status.h"
#include "core/burst.h"
#include "core/check.h"
#include "core/fmath.h"

int rsm_rev_config_default(rsm_rev_config_t *cfg)
{
    if (cfg == NULL) {
        return RSM_ERR_INVAL;
    }
    memset(cfg, 0, sizeof *cfg);
    cfg->clockwise = 1u;
    cfg->deskew = 1u;
    cfg->keep_every = 1u;
    cfg->min_points = 30u;
    cfg->wrap_deg = 180.0f;
    cfg->max_gap_us = 300000u;
    /* as the aligner's max_wait_us: odometry later than that is no help */
    cfg->odom_wait_us = 250000u;
    return RSM_OK;
}

static int pose_finite(const rsm_pose_t *p)
{
    return isfinite(p->x) && isfinite(p->y) && isfinite(p->theta);
}

/* Whether rsm_rev_init set r up (not for NULL, zeroed or stale memory). */
static int ready(const rsm_rev_t *r)
{
    return r != NULL && r->magic == (uint32_t)RSM_REV_MAGIC && r->cfg != NULL;
}

int rsm_rev_init_checked(rsm_rev_t *r, size_t r_size, unsigned long fingerprint, const rsm_rev_config_t *cfg)
{
    if (!RSM_SAME_BUILD(rsm_rev_t, r_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (r == NULL || cfg == NULL || cfg->keep_every == 0u || cfg->min_points == 0u ||
        !(cfg->wrap_deg > 0.0f && cfg->wrap_deg < 360.0f) || cfg->max_gap_us == 0u ||
        cfg->clockwise > 1u || cfg->deskew > 1u || cfg->upside_down > 1u ||
        !pose_finite(&cfg->mount)) {
        return RSM_ERR_INVAL;
    }
    memset(r, 0, sizeof *r);
    r->magic = (uint32_t)RSM_REV_MAGIC;
    r->cfg = cfg;
    return RSM_OK;
}

/* Signed microseconds a - b as a float (differences within a turn and the
 * odometry it spans are far below 2^31 us). */
static float us_between(uint64_t a, uint64_t b)
{
    return a >= b ? (float)(uint32_t)(a - b) : -(float)(uint32_t)(b - a);
}

/* Pose k of the odometry ring, oldest first. */
static const rsm_pose_t *odom_pose(const rsm_rev_t *r, size_t k, uint64_t *stamp)
{
    const size_t slot = (r->odom_head + k) % RSM_REV_ODOM_DEPTH;
    *stamp = r->odom_us[slot];
    return &r->odom[slot];
}

/* The shortest time a speed is measured over when the pose is extrapolated
 * past the newest odometry pose. */
#define REV_MIN_SPAN_US 20000u

/* The robot pose at time t (needs at least one odometry pose). */
static rsm_pose_t pose_at(rsm_rev_t *r, uint64_t t)
{
    uint64_t ta;
    uint64_t tb;
    const rsm_pose_t *a;
    const rsm_pose_t *b;
    rsm_pose_t out;
    float u;
    size_t k = 1;
    if (r->odom_n == 1u) {
        a = odom_pose(r, 0, &ta);
        r->stats.extrapolated += t != ta ? 1u : 0u;
        return *a;
    }
    a = odom_pose(r, 0, &ta);
    if (t < ta) {
        r->stats.extrapolated++;
        return *a; /* before the oldest: held */
    }
    b = odom_pose(r, 1, &tb);
    while (tb < t && k + 1u < r->odom_n) {
        k++;
        a = b;
        ta = tb;
        b = odom_pose(r, k, &tb);
    }
    if (t > tb) {
        /* Past the newest: the last motion goes on, measured over at least
         * REV_MIN_SPAN_US (samples read in a burst, microseconds apart,
         * would make any tick a speed of metres a millisecond) and over as
         * long as it is carried on, and for no longer than it was measured
         * over. */
        size_t j = k - 1u; /* a's */
        r->stats.extrapolated++;
        while (j > 0u && (us_between(tb, ta) < (float)REV_MIN_SPAN_US || us_between(tb, ta) < us_between(t, tb))) {
            a = odom_pose(r, --j, &ta);
        }
        if (us_between(tb, ta) < (float)REV_MIN_SPAN_US / 4.0f) {
            return *b; /* no span to measure a speed over: held */
        }
        if (us_between(t, tb) > us_between(tb, ta)) {
            t = tb + (tb - ta);
        }
    }
    if (tb == ta) {
        return *b;
    }
    u = us_between(t, ta) / us_between(tb, ta);
    out.x = a->x + (b->x - a->x) * u;
    out.y = a->y + (b->y - a->y) * u;
    out.theta = rsm_wrap_angle(a->theta + rsm_wrap_angle(b->theta - a->theta) * u);
    return out;
}

/* The longest a turn may last: no spinning lidar turns slower than 0.5
 * Hz; a longer one is a sensor angle that stopped moving. */
#define REV_MAX_TURN_US 2000000u

/* The fastest the robot may move: odometry that says more (a spike, a
 * counter reset, absurd poses) is no motion to de-skew by. */
#define REV_MAX_SPEED_M_S 5.0f
#define REV_MAX_TURN_RAD_S (4.0f * RSM_PI)

/* Whether motion over dt_s seconds is one a robot can make (and finite). */
static int plausible(const rsm_pose_t *m, float dt_s)
{
    const float d = REV_MAX_SPEED_M_S * dt_s + 0.001f;
    const float d2 = m->x * m->x + m->y * m->y;
    return d2 <= d * d && fabsf(m->theta) <= REV_MAX_TURN_RAD_S * dt_s + 0.001f;
}

/* Bearing in the laser frame (CCW, radians, (-pi, pi]) of sensor angle a. */
static float bearing(const rsm_rev_config_t *cfg, float a_deg)
{
    const float a = a_deg * (RSM_PI / 180.0f);
    return rsm_wrap_angle(cfg->clockwise ? -a : a);
}

/* Fills r->scan from turn t; rsm_rev_push returns 1 for it next. */
static void deliver(rsm_rev_t *r, const rsm_rev_turn_t *t)
{
    const rsm_rev_config_t *cfg = r->cfg;
    const uint64_t stamp = t->first_us + (t->last_us - t->first_us) / 2u;
    const int deskew = cfg->deskew && r->odom_n > 0u;
    const rsm_pose_t inv_mount = rsm_pose_inverse(&cfg->mount);
    rsm_pose_t at_stamp = {0.0f, 0.0f, 0.0f};
    size_t i;
    if (cfg->deskew && !deskew) {
        r->stats.not_deskewed++;
    }
    if (deskew) {
        at_stamp = pose_at(r, stamp);
    }
    for (i = 0; i < t->n; ++i) {
        const float b = bearing(cfg, t->angle_deg[i]);
        const float range = t->range_m[i];
        r->scan.angle_rad[i] = b;
        r->scan.range_m[i] = range;
        if (range == 0.0f) {
            r->stats.invalid++;
        } else if (deskew) {
            /* laser frame at the point's time -> robot frame -> robot frame
             * at the stamp -> laser frame at the stamp */
            const uint64_t when = t->first_us + t->dt_us[i];
            const rsm_pose_t then = pose_at(r, when);
            const rsm_pose_t motion = rsm_pose_between(&at_stamp, &then);
            rsm_point_t p;
            if (!plausible(&motion, fabsf(us_between(when, stamp)) * 1e-6f)) {
                r->stats.implausible++; /* NaN fails too: left as measured */
                continue;
            }
            rsm_sincosf(b, &p.y, &p.x);
            p.x *= range;
            p.y *= range;
            if (cfg->upside_down) {
                p.y = -p.y;
            }
            p = rsm_pose_apply(&cfg->mount, &p);
            p = rsm_pose_apply(&motion, &p);
            p = rsm_pose_apply(&inv_mount, &p);
            if (cfg->upside_down) {
                p.y = -p.y;
            }
            r->scan.range_m[i] = sqrtf(p.x * p.x + p.y * p.y);
            r->scan.angle_rad[i] = rsm_atan2f(p.y, p.x);
        }
    }
    r->scan.count = t->n;
    r->scan.stamp_us = stamp;
    r->stats.scans++;
    r->unsaid = 1u;
}

/* Whether odometry covers the turn that ended at last_us for good: a pose
 * stamped at or after it that no burst will re-stamp any more (one before
 * the newest, or the newest once RSM_BURST_US passed without a partner;
 * now_us is the newest point's stamp). */
static int covered(const rsm_rev_t *r, uint64_t last_us, uint64_t now_us)
{
    uint64_t t_new;
    uint64_t t_prev;
    if (r->odom_n == 0u) {
        return 0;
    }
    (void)odom_pose(r, r->odom_n - 1u, &t_new);
    if (t_new < last_us) {
        return 0;
    }
    if (r->odom_n >= 2u) {
        (void)odom_pose(r, r->odom_n - 2u, &t_prev);
        if (t_prev >= last_us) {
            return 1;
        }
    }
    return now_us > t_new && now_us - t_new > RSM_BURST_US;
}

/* Whether the turn that ended at last_us should be de-skewed now, at now_us:
 * odometry covers it, or waiting is no use (de-skew off, no wait set, no
 * odometry, or none for odom_wait_us: the newest pose being older than the
 * turn's end, a turn waits at most that long past it). */
static int wait_over(const rsm_rev_t *r, uint64_t last_us, uint64_t now_us)
{
    const uint64_t wait = r->cfg->odom_wait_us;
    uint64_t t_new;
    if (!r->cfg->deskew || wait == 0u || r->odom_n == 0u || covered(r, last_us, now_us)) {
        return 1;
    }
    (void)odom_pose(r, r->odom_n - 1u, &t_new);
    return now_us > t_new && now_us - t_new >= wait;
}

/* De-skews the held turn now, with the odometry there is. */
static void release(rsm_rev_t *r)
{
    uint64_t t_new = 0u;
    if (r->odom_n > 0u) {
        (void)odom_pose(r, r->odom_n - 1u, &t_new);
    }
    if (r->odom_n == 0u || t_new < r->held.last_us) {
        r->stats.uncovered++;
    }
    r->holding = 0u;
    deliver(r, &r->held);
}

/* A whole turn: de-skewed now, or held until odometry covers it. A turn
 * held already goes first; only one turn a call is returned. */
static void turn_ended(rsm_rev_t *r, uint64_t now_us)
{
    if (r->holding) {
        release(r); /* the next turn ended first */
    }
    if (!r->unsaid && wait_over(r, r->cur.last_us, now_us)) {
        deliver(r, &r->cur);
        return;
    }
    r->held.n = r->cur.n;
    r->held.first_us = r->cur.first_us;
    r->held.last_us = r->cur.last_us;
    memcpy(r->held.angle_deg, r->cur.angle_deg, r->cur.n * sizeof r->cur.angle_deg[0]);
    memcpy(r->held.range_m, r->cur.range_m, r->cur.n * sizeof r->cur.range_m[0]);
    memcpy(r->held.dt_us, r->cur.dt_us, r->cur.n * sizeof r->cur.dt_us[0]);
    r->holding = 1u;
    r->stats.waited++;
}

int rsm_rev_odometry(rsm_rev_t *r, uint64_t stamp_us, const rsm_pose_t *pose)
{
    size_t slot;
    if (!ready(r) || pose == NULL) {
        return RSM_ERR_INVAL;
    }
    if (!pose_finite(pose)) {
        r->stats.odometry_bad++;
        return RSM_ERR_RANGE;
    }
    if (r->odom_n > 0u &&
        stamp_us < r->odom_us[(r->odom_head + r->odom_n - 1u) % RSM_REV_ODOM_DEPTH]) {
        r->stats.odometry_bad++;
        return RSM_ERR_ORDER;
    }
    if (r->odom_n >= 2u) {
        /* A burst (core/burst.h): the newest is put halfway between the
         * one before and this one; its pose is kept. */
        const size_t newest = (r->odom_head + r->odom_n - 1u) % RSM_REV_ODOM_DEPTH;
        const size_t before = (r->odom_head + r->odom_n - 2u) % RSM_REV_ODOM_DEPTH;
        if (rsm_burst_restamp(r->odom_us[before], &r->odom_us[newest], stamp_us)) {
            r->stats.odometry_bursts++;
        }
    }
    if (r->odom_n == RSM_REV_ODOM_DEPTH) {
        uint64_t second;
        (void)odom_pose(r, 1, &second);
        if (r->holding && !r->unsaid && second > r->held.first_us) {
            /* The oldest pose is the held turn's start: de-skewed with it
             * now (rsm_rev_push returns the turn next), not without it. */
            release(r);
        }
        r->odom_head = (r->odom_head + 1u) % RSM_REV_ODOM_DEPTH;
        r->odom_n--;
    }
    slot = (r->odom_head + r->odom_n) % RSM_REV_ODOM_DEPTH;
    r->odom_us[slot] = stamp_us;
    r->odom[slot] = *pose;
    r->odom_n++;
    r->stats.odometry++;
    return RSM_OK;
}

/* Ends the turn in progress without delivering it. */
static void drop_turn(rsm_rev_t *r)
{
    if (r->seen > 0u) {
        r->stats.partial++;
        r->stats.dropped += (uint32_t)r->cur.n;
    }
    r->cur.n = 0;
    r->seen = 0;
}

void rsm_rev_reset(rsm_rev_t *r)
{
    if (!ready(r)) {
        return;
    }
    drop_turn(r);
    r->have_last = 0u;
    r->whole = 0u;
}

int rsm_rev_flush(rsm_rev_t *r)
{
    if (!ready(r)) {
        return RSM_ERR_INVAL;
    }
    if (!r->unsaid && r->holding) {
        release(r);
    }
    if (r->unsaid) {
        r->unsaid = 0u;
        return 1;
    }
    return 0;
}

int rsm_rev_push(rsm_rev_t *r, const rsm_lidar_point_t *pt)
{
    const rsm_rev_config_t *cfg;
    if (!ready(r) || pt == NULL) {
        return RSM_ERR_INVAL;
    }
    cfg = r->cfg;
    if (!(pt->angle_deg >= 0.0f && pt->angle_deg < 360.0f) ||
        !(pt->range_m >= 0.0f && isfinite(pt->range_m))) {
        r->stats.bad_points++;
        return RSM_ERR_RANGE;
    }
    if (r->have_last && pt->stamp_us < r->last_us) {
        r->stats.bad_points++;
        return RSM_ERR_ORDER;
    }
    r->stats.points++;
    if (r->holding && !r->unsaid && wait_over(r, r->held.last_us, pt->stamp_us)) {
        release(r);
    }
    if (r->have_last && pt->stamp_us - r->last_us > cfg->max_gap_us) {
        r->stats.gaps++;
        drop_turn(r);
        r->whole = 0u;
    } else if (r->seen > 0u && r->last_us - r->cur.first_us > REV_MAX_TURN_US) {
        /* its points span over 2 s (a pause after them is not counted: a
         * replayed log may pause between turns) */
        r->stats.long_turns++;
        drop_turn(r);
        r->whole = 0u;
    } else if (r->have_last && r->last_angle - pt->angle_deg > cfg->wrap_deg) {
        if (r->whole && r->cur.n >= cfg->min_points) {
            r->cur.last_us = r->last_us;
            turn_ended(r, pt->stamp_us);
            r->cur.n = 0;
            r->seen = 0;
        } else {
            drop_turn(r);
        }
        r->whole = 1u;
    }
    if (r->seen == 0u) {
        r->cur.first_us = pt->stamp_us;
    }
    if (r->seen++ % cfg->keep_every != 0u) {
        r->stats.thinned++;
    } else if (r->cur.n == (size_t)RSM_MAX_BEAMS) {
        r->stats.overflow++;
    } else {
        r->cur.angle_deg[r->cur.n] = pt->angle_deg;
        r->cur.range_m[r->cur.n] = pt->range_m;
        r->cur.dt_us[r->cur.n] = (uint32_t)(pt->stamp_us - r->cur.first_us);
        r->cur.n++;
    }
    r->last_us = pt->stamp_us;
    r->last_angle = pt->angle_deg;
    r->have_last = 1u;
    if (r->unsaid) {
        r->unsaid = 0u;
        return 1;
    }
    return 0;
}
