/* A configuration for microcontrollers with 64 KiB of RAM to spare: select
 * it with -DRSM_USER_CONFIG=rsm/config_small.h (CMake option
 * RSM_USER_CONFIG). The persistent map holds 1140 tiles at 10, 20 and 40 cm
 * (about the whole Intel lab, most of the ACES building; the least recently
 * written tiles are reused beyond that): with so few tiles, 5 cm cells would
 * forget the building too soon. The global search keeps 24 readings, 4
 * candidates and bound grids of 16 blocks a side (60 tiles gave way for
 * it), searches every heading the default searches every other of, and
 * each bar once where the default searches the first twice and each lower
 * one three times: with so few readings and poses kept, the coarser
 * lattice and the repeated searches proved look-alikes on ACES. Under
 * 64 KiB of localizer state; tools/bench prints its accuracy beside the
 * default's. */
#ifndef RSM_CONFIG_SMALL_H
#define RSM_CONFIG_SMALL_H
#define RSM_TMAP_TILES 1140
#define RSM_TMAP_HASH_LOG2 11
#define RSM_TMAP_LEVELS 3
#define RSM_TMAP_CELL_M 0.1f
#define RSM_MAP_SIZE_LOG2 6
#define RSM_MAX_KEYPOINTS 32
#define RSM_MAX_CANDIDATES 384
#define RSM_MAX_MATCHES 96
#define RSM_GLOBAL_SIDE 16
#define RSM_GLOBAL_POINTS 24
#define RSM_GLOBAL_CANDIDATES 4
#define RSM_GLOBAL_HEADING_CELLS 1
#define RSM_GLOBAL_BAR_SEARCHES 1
#define RSM_GLOBAL_FIRST_SEARCHES 1
#endif
