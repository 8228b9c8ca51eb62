/* What the modules that replace the localizer's persistent map (mapfile.c,
 * mapimport.c, tilestore.c) share with the localizer (localizer.c) and
 * with each other. Internal. */
#ifndef RSM_MAPSTATE_H
#define RSM_MAPSTATE_H

#include "rsm/localizer.h"

/* 1 for a localizer rsm_localizer_init set up (magic and cfg), else 0. */
int rsm_localizer_ready(const rsm_localizer_t *loc);

/* The persistent map was emptied or replaced (a load that failed once
 * reading began, an import begun, or below): the global search's grids and
 * its take-back from the store stand for it no more. */
void rsm_localizer_map_cleared(rsm_localizer_t *loc);

/* The persistent map was replaced (loaded, imported): the next scan is
 * matched against it, not written as a first; writes count from the
 * estimate; fit (0: unknown) is the recent scans' and the map's own; the
 * global search's grids are built for it, and a search under way starts
 * over in the new map. */
void rsm_localizer_map_replaced(rsm_localizer_t *loc, float fit);

/* One tile of a saved map's bytes (docs/mapfile.md: 40 bytes with the
 * default tile side), as mapfile.c reads it and the store over a saved map
 * in flash (tilestore.c) does. */
void rsm_mapfile_decode_tile(rsm_tile_t *t, const uint8_t *b);

#endif /* RSM_MAPSTATE_H */
