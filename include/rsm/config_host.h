/* A larger configuration for single-board computers and host replay:
 * select it with -DRSM_USER_CONFIG=rsm/config_host.h (CMake option
 * RSM_USER_CONFIG). 256 x 256 map cells (12.8 m at 5 cm), up to 721
 * readings per scan, more key points and matches, and a persistent map of
 * 16000 tiles (six times the default's). About 700 KiB of state. */
#ifndef RSM_CONFIG_HOST_H
#define RSM_CONFIG_HOST_H
#define RSM_MAX_BEAMS 721
#define RSM_MAP_SIZE_LOG2 8
#define RSM_MAX_KEYPOINTS 128
#define RSM_MAX_CANDIDATES 2048
#define RSM_MAX_MATCHES 512
#define RSM_TMAP_TILES 16000
#define RSM_TMAP_HASH_LOG2 15
#endif
