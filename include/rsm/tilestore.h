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
 * rsm_tilestore_mem_t below is one in caller-supplied memory (no heap),
 * rsm_tilestore_rom_t one over a saved map in memory-mapped flash. */
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

/* A store over a saved map kept in memory-mapped flash (rsm/mapfile.h),
 * for localization mode on a target whose RAM holds only the pool: the
 * tiles stay in the map's bytes, an index of 2^index_log2 words, in flash
 * too, finds them, and a bitmap in RAM, one bit a tile, says which are out
 * in the pool. A map mapped once (on a host with rsm-nav --tile-store, or
 * on the robot) is written into flash, its index built there once
 * (rsm_tilestore_rom_build_index), and each boot loads it
 * (rsm_localizer_load_map over the same bytes: the pool takes the coarse
 * levels, and every other tile is "put" here, which only marks it held).
 * A tile let go comes back here only as it was in the map: one a map
 * update changed is refused (RSM_ERR_NOMEM, counted in the map's
 * counters.unstored), so with map_frozen = 0 such places are forgotten
 * once the pool lets them go. */
typedef struct rsm_tilestore_rom {
    const uint8_t *map;         /* the saved map's bytes, as rsm_localizer_save_map wrote them */
    uint32_t tiles;             /* its tiles */
    const uint32_t *index;      /* 2^index_log2 words: a tile's number, 0xFFFFFFFF empty (erased) */
    uint32_t index_log2;
    uint8_t *out;               /* (tiles + 7) / 8 bytes: bit k set while tile k is not held here */
    uint32_t held;
} rsm_tilestore_rom_t;

/* Index words for a map of `tiles` tiles, as a log2: the smallest power of
 * two at least 4/3 of it (at least 2). */
uint32_t rsm_tilestore_rom_index_log2(uint32_t tiles);

/* Programs one 32-bit word of the index (word number `at`, erased before:
 * every word is programmed at most once); 0 on success. */
typedef int (*rsm_tilestore_program_fn)(void *ctx, uint32_t at, uint32_t value);

/* Builds the index of the map that begins the len bytes at `map` (its
 * saved bytes, or a larger flash region that starts with them: the map's
 * length is in its header) into an erased region
 * of 2^index_log2 words that `index` reads (memory-mapped) and `program`
 * writes. RSM_OK; RSM_ERR_INVAL for NULL pointers or an index smaller than
 * rsm_tilestore_rom_index_log2 asks; RSM_ERR_FORMAT for bytes that are no
 * map (magic, or a length past len), or a place held twice; RSM_ERR_IO when program
 * failed, or the region was not erased. The map's CRC is the load's to
 * check. */
int rsm_tilestore_rom_build_index(const uint8_t *map, uint32_t len, const uint32_t *index, uint32_t index_log2,
                                  rsm_tilestore_program_fn program, void *ctx);

/* Sets m up over a map's bytes (as above: len at least its length), its
 * index (built as above) and out
 * ((tiles + 7) / 8 bytes of RAM), holding nothing until a load puts the
 * tiles the pool cannot hold, and *store to its callbacks. RSM_OK;
 * RSM_ERR_INVAL for NULL pointers, an index too small or out too short;
 * RSM_ERR_FORMAT for bytes that are no map. */
int rsm_tilestore_rom_init(rsm_tilestore_rom_t *m, const uint8_t *map, uint32_t len, const uint32_t *index,
                           uint32_t index_log2, uint8_t *out, uint32_t out_bytes, rsm_tile_store_t *store);

#ifdef __cplusplus
}
#endif

#endif /* RSM_TILESTORE_H */
