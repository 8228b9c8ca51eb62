/* What the spinning-lidar decoders (rsm/ld06.h, rsm/rplidar.h) give and the
 * revolution assembler (rsm/revolution.h) takes: one measured point in the
 * sensor's own angle convention, before any mounting or motion is applied. */
#ifndef RSM_LIDAR_H
#define RSM_LIDAR_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct rsm_lidar_point {
    float angle_deg; /* sensor angle in [0, 360), growing the way the head turns
                        (clockwise seen from above for the RPLIDAR and the LD06) */
    float range_m;   /* metres; 0 means "no measurement" (the sensors' own code) */
    uint8_t quality; /* RPLIDAR quality (0..63) or LD06 intensity (0..255) */
    uint8_t start;   /* 1: the sensor flagged this point as the first of a new
                        turn (RPLIDAR standard scan S bit); 0 otherwise */
    uint64_t stamp_us; /* host clock time the point was measured at: 0 from the
                          codecs (they know no time), set by the drivers */
} rsm_lidar_point_t;

#ifdef __cplusplus
}
#endif

#endif /* RSM_LIDAR_H */
