#include "replay.h"

#include <string.h>

#include "fmt.h"
#include "replay_data.h"
#include "rsm/geom.h"
#include "rsm/status.h"

typedef char rsm_replay_beams_fit[(RSM_REPLAY_BEAMS <= RSM_MAX_BEAMS) ? 1 : -1];

void rsm_replay_put_str(const rsm_replay_io_t *io, const char *s)
{
    io->write(io->ctx, s, strlen(s));
}

void rsm_replay_put_dec(const rsm_replay_io_t *io, uint32_t v)
{
    char buf[RSM_FMT_DEC_MAX];
    const size_t first = rsm_fmt_dec(buf, v);
    io->write(io->ctx, buf + first, sizeof buf - first);
}

void rsm_replay_put_hex(const rsm_replay_io_t *io, uint32_t v)
{
    char buf[8];
    rsm_fmt_hex(buf, v);
    io->write(io->ctx, buf, sizeof buf);
}

/* A float's bits: what the host and the target must agree on. */
static void put_bits(const rsm_replay_io_t *io, float f)
{
    uint32_t b;
    memcpy(&b, &f, sizeof b);
    rsm_replay_put_str(io, " ");
    rsm_replay_put_hex(io, b);
}

static void put_report(const rsm_replay_io_t *io, uint32_t scan, const rsm_localizer_report_t *rep, uint32_t odo)
{
    uint32_t s;
    rsm_replay_put_str(io, "P ");
    rsm_replay_put_dec(io, scan);
    rsm_replay_put_str(io, " ");
    rsm_replay_put_dec(io, (uint32_t)rep->outcome);
    put_bits(io, rep->pose.x);
    put_bits(io, rep->pose.y);
    put_bits(io, rep->pose.theta);
    rsm_replay_put_str(io, "\n");
    if (io->clock_fn == NULL) {
        return;
    }
    if (rep->recovering) {
        /* The scans a tracking recovery took, for the cost of one. */
        rsm_replay_put_str(io, "R ");
        rsm_replay_put_dec(io, scan);
        rsm_replay_put_str(io, "\n");
    }
    rsm_replay_put_str(io, "T ");
    rsm_replay_put_dec(io, scan);
    rsm_replay_put_str(io, " ");
    rsm_replay_put_dec(io, rep->step_time);
    for (s = 0; s < (uint32_t)RSM_STAGE_COUNT; ++s) {
        rsm_replay_put_str(io, " ");
        rsm_replay_put_dec(io, rep->stage_time[s]);
    }
    rsm_replay_put_str(io, " ");
    rsm_replay_put_dec(io, odo);
    rsm_replay_put_str(io, "\n");
}

int rsm_replay_run(rsm_replay_t *r, const rsm_replay_io_t *io)
{
    const rsm_pose_t start = {0.0f, 0.0f, 0.0f};
    uint32_t i;
    uint32_t odo = 0u; /* clock_fn time in the encoder steps since the last scan */
    int rc;
    r->cfg = rsm_localizer_config_default();
    r->cfg.clock_fn = io->clock_fn;
    r->cfg.clock_ctx = io->clock_ctx;
    rc = rsm_localizer_init(&r->loc, &r->cfg, &start, NULL);
    if (rc != RSM_OK) {
        return rc;
    }
    for (i = 0; i < rsm_replay_step_count; ++i) {
        const rsm_replay_step_t *st = &rsm_replay_steps[i];
        /* The encoder steps are part of a scan's cost on a robot: timed
         * here, outside the report's step_time, and added in the T line. */
        if (io->clock_fn != NULL) {
            const uint32_t t0 = io->clock_fn(io->clock_ctx);
            (void)rsm_localizer_ticks(&r->loc, st->left, st->right);
            odo += io->clock_fn(io->clock_ctx) - t0;
        } else {
            (void)rsm_localizer_ticks(&r->loc, st->left, st->right);
        }
        if (st->scan != 0u && st->scan <= rsm_replay_scan_count) {
            const rsm_replay_scan_t *sc = &rsm_replay_scans[st->scan - 1u];
            uint32_t b;
            for (b = 0; b < RSM_REPLAY_BEAMS; ++b) {
                r->scan.range_m[b] = (float)sc->range_cm[b] * 0.01f;
            }
            (void)rsm_scan_set_uniform(&r->scan, RSM_REPLAY_BEAMS, -RSM_PI / 2.0f, RSM_PI / (float)RSM_REPLAY_BEAMS);
            r->scan.stamp_us = sc->stamp_us;
            (void)rsm_localizer_scan(&r->loc, &r->scan, &r->rep);
            put_report(io, (uint32_t)st->scan - 1u, &r->rep, odo);
            odo = 0u;
        }
    }
    rsm_replay_put_str(io, "E scans ");
    rsm_replay_put_dec(io, r->loc.counters.scans);
    rsm_replay_put_str(io, " accepted ");
    rsm_replay_put_dec(io, r->loc.counters.outcome[RSM_SCAN_ACCEPTED]);
    rsm_replay_put_str(io, " out_of_order ");
    rsm_replay_put_dec(io, r->loc.counters.outcome[RSM_SCAN_OUT_OF_ORDER]);
    rsm_replay_put_str(io, " motions ");
    rsm_replay_put_dec(io, r->loc.counters.motions);
    rsm_replay_put_str(io, "\n");
    return RSM_OK;
}
