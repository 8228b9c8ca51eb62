/* Where the map's tiles go when its pool lets them go, so that a building
 * larger than the pool is kept whole: external RAM, a file on a host, a
 * flash region on a microcontroller (docs/map.md, "A store behind the
 * pool").
 *
 * Without a store, a full pool reuses the slot of the tile written longest
 * ago and that place is forgotten. With one (rsm_localizer_set_store), the
 * tile goes to the store first, and comes back when the robot returns:
 * before each scan is matched, the tiles under its points at the predicted
 * pose (and those a match may reach) are taken back from the store, and a
 * return written into a place the store holds starts from the stored tile.
 * A tile is in the pool or in the store, never both. A saved map
 * (rsm/mapfile.h) holds both, and loading one puts what the pool cannot
 * hold into the store.
 *
 * What differs from a pool without a limit: beams passing through a place
 * only the store holds do not clear it (a stored tile comes back only
 * under a scan's returns); the whole-map search (rsm_localizer_global)
 * searches the pool alone (after a load, the coarse levels of the whole
 * map, rsm/mapfile.h), and rsm_localizer_map_occupancy and
 * rsm_localizer_map_bounds read the pool alone.
 *
 * The store is the caller's: rsm_tile_store_t is a table of callbacks.
 * rsm_tilestore_mem_t below is one in caller-supplied memory (no heap). */
#ifndef RSM_TILESTORE_H
#define RSM_TILESTORE_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/localizer.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct rsm_tile_store {
    void *ctx;
    /* Tiles it can hold at most (a map's load checks it has the room). */
    uint32_t capacity;
    /* Keeps a copy of t (its level in the stamp's top two bits). RSM_OK;
     * RSM_ERR_NOMEM when full; RSM_ERR_FORMAT when it holds that place
     * already. On an error the tile is lost (counted in the map's
     * counters.unstored). */
    int (*put)(void *ctx, const rsm_tile_t *t);
    /* Moves the tile of (level, tx, ty) out into *t: 1 when it held one
     * (and no longer does), 0 when not. */
    int (*take)(void *ctx, uint32_t level, int32_t tx, int32_t ty, rsm_tile_t *t);
    /* Tiles held now. */
    uint32_t (*count)(const void *ctx);
    /* Copies the i-th tile held (0 <= i < count, in any order that stays
     * the same while nothing is put or taken) into *t; RSM_OK, else
     * RSM_ERR_RANGE. */
    int (*at)(const void *ctx, uint32_t i, rsm_tile_t *t);
    /* Forgets every tile. */
    void (*clear)(void *ctx);
} rsm_tile_store_t;

/* Gives loc's map (RSM_METHOD_MAP) the store, from now on; NULL: none (the
 * tiles it holds stay there, no longer part of the map). The store must
 * outlive its use and be empty or hold this map's tiles (a load fills it);
 * rsm_localizer_init forgets it. RSM_OK; RSM_ERR_INVAL for loc never
 * initialised or a callback missing; RSM_ERR_NOSYS for another method. */
int rsm_localizer_set_store(rsm_localizer_t *loc, const rsm_tile_store_t *store);

/* A store in memory the caller supplies: tiles[capacity] and an index of
 * 2^index_log2 entries (at least 4/3 of capacity, for short probes). */
typedef struct rsm_tilestore_mem {
    rsm_tile_t *tile;
    uint32_t *index;      /* slot + 1 of a place, 0 empty; linear probing */
    uint32_t capacity;
    uint32_t index_log2;
    uint32_t used;
} rsm_tilestore_mem_t;

/* Index entries for a capacity: the smallest power of two at least 4/3 of
 * it, as a log2 (at least 2). */
uint32_t rsm_tilestore_mem_index_log2(uint32_t capacity);

/* Sets m up over tiles[capacity] and index[1 << index_log2], empty, and
 * *store to its callbacks. RSM_OK; RSM_ERR_INVAL for a NULL pointer, a
 * capacity of 0 or beyond 2^28, or an index smaller than
 * rsm_tilestore_mem_index_log2(capacity) asks. A macro, as
 * rsm_localizer_init: it passes the caller's sizeof(rsm_tile_t) and
 * RSM_CONFIG_FINGERPRINT, so that a caller built with another tile size
 * gets RSM_ERR_CONFIG, with nothing written. */
#define rsm_tilestore_mem_init(m, tiles, capacity, index, index_log2, store)                            \
    rsm_tilestore_mem_init_checked((m), (tiles), (capacity), (index), (index_log2), (store), sizeof(rsm_tile_t), \
                                   (unsigned long)RSM_CONFIG_FINGERPRINT)

int rsm_tilestore_mem_init_checked(rsm_tilestore_mem_t *m, rsm_tile_t *tiles, uint32_t capacity, uint32_t *index,
                                   uint32_t index_log2, rsm_tile_store_t *store, size_t tile_size,
                                   unsigned long fingerprint);

#ifdef __cplusplus
}
#endif

#endif /* RSM_TILESTORE_H */
