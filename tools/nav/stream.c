#include "stream.h"

#include <string.h>

#include "rsm/sicklms.h"
#include "rsm/status.h"

void nav_stream_init(nav_stream_t *s)
{
    memset(s, 0, sizeof *s);
    (void)rsm_aria_parser_init(&s->aria);
    (void)rsm_lms_parser_init(&s->lms);
}

void nav_stream_robot(nav_stream_t *s, const uint8_t *data, size_t n, uint64_t stamp_us,
                      const nav_stream_sink_t *sink)
{
    size_t off = 0;
    do {
        rsm_aria_packet_t pkt;
        size_t used = 0;
        const int got = rsm_aria_parser_feed(&s->aria, data + off, n - off, &used, &pkt);
        off += used;
        if (got != 1) {
            break;
        }
        {
            rsm_aria_encoder_t enc;
            if (rsm_aria_decode_encoder(&pkt, &enc) == RSM_OK) {
                rsm_odometry_sample_t smp;
                smp.stamp_us = stamp_us;
                smp.left = (uint32_t)enc.left;
                smp.right = (uint32_t)enc.right;
                s->encoder_packets++;
                sink->encoder(sink->ctx, &smp, 0);
            } else {
                s->other_packets++;
            }
        }
    } while (off < n || rsm_aria_parser_pending(&s->aria) > 0u);
    /* After the packets: one past a waiting scan releases it exactly. */
    if (sink->tick != NULL) {
        sink->tick(sink->ctx, stamp_us);
    }
}

void nav_stream_laser(nav_stream_t *s, const uint8_t *data, size_t n, uint64_t stamp_us,
                      const nav_stream_sink_t *sink)
{
    size_t off = 0;
    /* A telegram is stamped when its first byte arrived: at 38400 baud a
     * 361-reading telegram is on the wire for about 0.2 s after the scan. */
    uint64_t start_us = rsm_lms_parser_pending(&s->lms) > 0u ? s->lms_start_us : stamp_us;
    while (off < n) {
        rsm_lms_event_t ev;
        uint64_t t_us;
        size_t used = 0;
        const int got = rsm_lms_parser_feed(&s->lms, data + off, n - off, &used, &ev);
        off += used;
        if (got != 1) {
            break;
        }
        t_us = start_us;
        start_us = stamp_us; /* what follows in this chunk starts the next one */
        if (ev.type != RSM_LMS_EVENT_TELEGRAM || ev.telegram.cmd != 0xB0u) {
            s->other_packets++;
            continue;
        }
        if (rsm_lms_decode_b0(&ev.telegram, NULL, &s->lms_scan) != RSM_OK ||
            rsm_sicklms_to_scan(&s->lms_scan, 0u, &s->scan) < 0) {
            s->bad_scans++;
            continue;
        }
        s->scan.stamp_us = t_us;
        s->lms_scans++;
        sink->scan(sink->ctx, &s->scan, t_us);
    }
    s->lms_start_us = start_us;
    if (sink->tick != NULL) {
        sink->tick(sink->ctx, stamp_us);
    }
}
