/* Saving and loading the persistent map (RSM_METHOD_MAP), so that a robot
 * maps its building once and localizes in it after every power-up.
 *
 * The bytes go through caller-supplied callbacks at explicit offsets: a
 * file on a host (fseek/fread), a flash region on a microcontroller
 * (memory-mapped reads, page writes). The format (docs/mapfile.md) is
 * little-endian and versioned: a 48-byte header (magic "RSMM", version,
 * the library's capacity fingerprint, the map's cell size, levels and
 * saturation, the tile count, the write counter, the pose at the save and
 * how well scans then fitted the map),
 * the tiles held (40 bytes each with 8 x 8 cells), and a CRC-32 over all
 * of it. A map is as large as the tiles it holds: at most
 * RSM_MAPFILE_MAX_BYTES.
 *
 * Loading reads the whole map twice: once to check it (header, every
 * tile, the CRC) without writing anything, then to take it. A map that is
 * corrupt, truncated, or from another build (other capacities, other cell
 * size, levels or saturation, another version) is refused with loc as it
 * was. No heap, no global state; not reentrant for one localizer. */
#ifndef RSM_MAPFILE_H
#define RSM_MAPFILE_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/config.h"
#include "rsm/geom.h"
#include "rsm/localizer.h"

#ifdef __cplusplus
extern "C" {
#endif

#define RSM_MAPFILE_VERSION 1u
#define RSM_MAPFILE_HEADER_BYTES 48u
#define RSM_MAPFILE_TILE_BYTES (8u + (uint32_t)RSM_TMAP_TILE_BYTES)
/* The largest map this build writes: every slot of the pool in use. */
#define RSM_MAPFILE_MAX_BYTES \
    (RSM_MAPFILE_HEADER_BYTES + (uint32_t)RSM_TMAP_TILES * RSM_MAPFILE_TILE_BYTES + 4u)

/* Writes len bytes at offset; returns 0 on success, anything else on
 * failure (the save stops there with RSM_ERR_IO). */
typedef int (*rsm_mapfile_write_fn)(void *ctx, uint32_t offset, const uint8_t *buf, size_t len);

/* Reads len bytes at offset into buf; returns 0 when all len bytes were
 * read, anything else when they were not (an error, or the end of the
 * stored map: a truncated map). */
typedef int (*rsm_mapfile_read_fn)(void *ctx, uint32_t offset, uint8_t *buf, size_t len);

/* What a saved map holds besides its tiles (from its header). */
typedef struct rsm_mapfile_info {
    uint32_t bytes;   /* the whole map, header to CRC */
    uint32_t tiles;   /* tiles held, all levels */
    uint32_t stamp;   /* the map's write counter */
    rsm_pose_t pose;  /* the localizer's estimate when it was saved */
    float fit;        /* how well its recent scans fitted the map then (mean occupancy under
                       * their points, 0 to 1; 0: unknown): the bar a global search's
                       * winner is held to (rsm_localizer_global) */
} rsm_mapfile_info_t;

/* Bytes rsm_localizer_save_map would write now; 0 for loc NULL, never
 * initialised or of another method. */
uint32_t rsm_localizer_map_bytes(const rsm_localizer_t *loc);

/* Writes the persistent map (and the current estimate, as the pose to
 * resume from) through write, from offset 0, in pieces of at most one
 * tile. *info (may be NULL) gets what was written. Returns RSM_OK;
 * RSM_ERR_INVAL for NULL loc or write, or a localizer never initialised;
 * RSM_ERR_NOSYS for another method than RSM_METHOD_MAP; RSM_ERR_IO when
 * write failed (what it wrote is no map: its CRC is missing or wrong).
 * Reads loc only. A write into the map that is still spread over the
 * coming scans is saved as far as it went. */
int rsm_localizer_save_map(const rsm_localizer_t *loc, rsm_mapfile_write_fn write, void *ctx,
                           rsm_mapfile_info_t *info);

/* Checks the map read through read and, if it is sound, makes it loc's
 * persistent map: the next scan is matched against it (none starts a new
 * map), and how well recent scans fit is taken as saved. loc's estimate is left as it is: set it with rsm_localizer_set_pose
 * (for instance to info->pose, where the robot was when the map was
 * saved). Returns RSM_OK with *info (may be NULL) filled; else, with loc as
 * it was and *info untouched:
 *   RSM_ERR_INVAL   loc or read NULL, loc never initialised;
 *   RSM_ERR_NOSYS   loc's method is not RSM_METHOD_MAP;
 *   RSM_ERR_IO      read failed, or the map ends early (truncated);
 *   RSM_ERR_FORMAT  no "RSMM" magic, another version, another build's
 *                   capacities (RSM_CONFIG_FINGERPRINT), another cell
 *                   size, number of levels or saturation than loc's
 *                   configuration, a tile count beyond RSM_TMAP_TILES, or
 *                   a tile that cannot be (level, place, write counter,
 *                   twice held);
 *   RSM_ERR_CHECKSUM the CRC does not match: the map is corrupt.
 * Only when the second pass reads other bytes than the first (the storage
 * changed in between, or failed), or the map holds one place twice (which
 * no save writes, and only the second pass can see), is loc's map left
 * empty, with RSM_ERR_IO, RSM_ERR_CHECKSUM or RSM_ERR_FORMAT. */
int rsm_localizer_load_map(rsm_localizer_t *loc, rsm_mapfile_read_fn read, void *ctx, rsm_mapfile_info_t *info);

/* CRC-32 (the IEEE 802.3 / zlib polynomial, reflected, initial value and
 * final xor 0xFFFFFFFF) of len bytes, continuing from crc (0 to start). */
uint32_t rsm_crc32(uint32_t crc, const uint8_t *data, size_t len);

#ifdef __cplusplus
}
#endif

#endif /* RSM_MAPFILE_H */
