#include "stream.h"

#include <string.h>

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
                s->encoder_packets++;
                sink->encoder(sink->ctx, enc.left, enc.right, stamp_us);
            } else {
                s->other_packets++;
            }
        }
    } while (off < n || rsm_aria_parser_pending(&s->aria) > 0u);
}

void nav_stream_laser(nav_stream_t *s, const uint8_t *data, size_t n, uint64_t stamp_us,
                      const nav_stream_sink_t *sink)
{
    size_t off = 0;
    while (off < n) {
        rsm_lms_event_t ev;
        size_t used = 0;
        const int got = rsm_lms_parser_feed(&s->lms, data + off, n - off, &used, &ev);
        off += used;
        if (got != 1) {
            break;
        }
        if (ev.type != RSM_LMS_EVENT_TELEGRAM || ev.telegram.cmd != 0xB0u) {
            s->other_packets++;
            continue;
        }
        if (rsm_lms_decode_b0(&ev.telegram, NULL, &s->lms_scan) != RSM_OK || s->lms_scan.step_cdeg == 0u) {
            s->bad_scans++;
            continue;
        }
        {
            /* Scanner angles run 0..180 deg from the right; the robot's 0 is ahead. */
            const float step = (float)s->lms_scan.step_cdeg * (RSM_PI / 18000.0f);
            const float start = (float)s->lms_scan.start_cdeg * (RSM_PI / 18000.0f) - RSM_PI / 2.0f;
            size_t i;
            (void)rsm_scan_set_uniform(&s->scan, s->lms_scan.count, start, step);
            for (i = 0; i < s->lms_scan.count; ++i) {
                /* Invalid readings carry 0 m: the core drops and counts them. */
                s->scan.range_m[i] = s->lms_scan.reading[i].range_m;
            }
            s->scan.stamp_us = stamp_us;
            s->lms_scans++;
            sink->scan(sink->ctx, &s->scan, stamp_us);
        }
    }
}
