/* The replay firmware's compiled-in input: encoder counts and laser scans of
 * a CARMEN log excerpt, generated at build time by gen_replay_data.py (from
 * tests/data/intel_head.clf.gz), never committed. */
#ifndef RSM_REPLAY_DATA_H
#define RSM_REPLAY_DATA_H

#include <stdint.h>

#define RSM_REPLAY_BEAMS 180u /* readings per scan, over 180 degrees */

/* One encoder reading (cumulative counts); scan is the 1-based index of the
 * scan taken at this step's pose, 0 for none. */
typedef struct rsm_replay_step {
    uint32_t left;
    uint32_t right;
    uint16_t scan;
} rsm_replay_step_t;

typedef struct rsm_replay_scan {
    uint32_t stamp_us;                   /* since the first scan */
    uint16_t range_cm[RSM_REPLAY_BEAMS]; /* the log's ranges, centimetres */
} rsm_replay_scan_t;

extern const uint32_t rsm_replay_step_count;
extern const uint32_t rsm_replay_scan_count;
extern const rsm_replay_step_t rsm_replay_steps[];
extern const rsm_replay_scan_t rsm_replay_scans[];

#endif /* RSM_REPLAY_DATA_H */
