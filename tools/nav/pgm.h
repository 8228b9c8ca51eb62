/* Host-side global occupancy picture for rsm-nav's --map output: the
 * core's map scrolls and forgets, so the tool keeps every hit itself. */
#ifndef RSM_NAV_PGM_H
#define RSM_NAV_PGM_H

#include <stddef.h>

#include "rsm/geom.h"

typedef struct hitlist {
    rsm_point_t *pts;
    size_t count;
    size_t cap;
} hitlist_t;

int hitlist_add(hitlist_t *h, const rsm_point_t *p, size_t n);
void hitlist_free(hitlist_t *h);

/* Writes PGM (ROS map_server conventions: 0 occupied, 205 unknown) and a
 * YAML beside it (same name, .yaml). Returns 0 or -1. */
int pgm_write_map(const char *pgm_path, const hitlist_t *h, float resolution_m);

#endif
