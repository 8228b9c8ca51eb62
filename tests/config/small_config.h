/* A deliberately small configuration: the core tests run again against it so
 * that capacity limits and truncation paths are exercised. */
#ifndef RSM_SMALL_CONFIG_H
#define RSM_SMALL_CONFIG_H
#define RSM_MAX_BEAMS 181
#define RSM_MAP_SIZE_LOG2 6
#define RSM_MAX_KEYPOINTS 16
#define RSM_MAX_CANDIDATES 256
#define RSM_MAX_MATCHES 32
#define RSM_ARIA_MAX_SONAR 8
#define RSM_ARIA_STR_SIZE 12
/* A pool that fills within seconds, so that eviction is exercised. */
#define RSM_TMAP_TILES 48
#define RSM_TMAP_HASH_LOG2 6
#define RSM_TMAP_LEVELS 3
#define RSM_TMAP_CELL_M 0.1f
/* Odd and tiny: every frame reaches a driver in many pieces. */
#define RSM_LINK_RX_CHUNK 7
#define RSM_REV_ODOM_DEPTH 4
/* The whole map searched once at the first bar, as the shipped small
 * preset does (rsm/config_small.h): with 48 tiles and 400 units a scan,
 * test_a_twin_where_the_winner_was_carried proves the niche only in that
 * schedule (with two searches at the first bar, none within its path:
 * its searches take about 200 scans each). */
#define RSM_GLOBAL_FIRST_SEARCHES 1
#endif
