/* Host-side global occupancy picture for rsm-nav's --map output: the
 * core's map forgets (it reuses its oldest tiles), so the tool keeps its own
 * picture: a hit count per cell of the image, in a hash table that grows
 * with the area seen, never with the number of scans. */
#ifndef RSM_NAV_PGM_H
#define RSM_NAV_PGM_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/geom.h"

/* The picture spans at most this many cells a side (1 km at 5 cm). */
#define PGM_MAX_SIDE 20000
/* Points this far from the origin or farther are not placed (the core's
 * limit on coordinates, see docs/robustness.md). */
#define PGM_MAX_COORD_M 1.0e6f

typedef struct hitmap {
    float res_m;         /* cell size */
    uint64_t *keys;      /* cell (x, y) packed, 0 = empty slot */
    uint8_t *hits;       /* hits per cell, saturated at 255 */
    size_t cap;          /* slots, a power of two */
    size_t count;        /* cells used */
    int32_t min_x, min_y, max_x, max_y;
    uint64_t far;        /* points not placed: not finite or beyond PGM_MAX_COORD_M */
} hitmap_t;

/* Starts an empty picture with res_m cells. Returns 0 or -1 (bad size). */
int hitmap_init(hitmap_t *h, float res_m);

/* Adds n points (may be 0, p may then be NULL). Returns 0 or -1 (out of memory). */
int hitmap_add(hitmap_t *h, const rsm_point_t *p, size_t n);

void hitmap_free(hitmap_t *h);

/* Writes PGM (ROS map_server conventions: 0 occupied, 205 unknown) and a
 * YAML beside it (same name, .yaml). Returns 0, PGM_TOO_LARGE (the picture
 * would span more than PGM_MAX_SIDE cells; *w_m and *h_m say how far) or
 * -1 (cannot write; errno says why). The points are in a frame shifted by
 * (off_x, off_y) metres from the world's: the YAML origin adds it back. */
#define PGM_TOO_LARGE (-2)
int pgm_write_map(const char *pgm_path, const hitmap_t *h, double off_x, double off_y, double *w_m, double *h_m);

#endif
