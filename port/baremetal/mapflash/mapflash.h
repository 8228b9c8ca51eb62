/* The map-in-flash example: a robot maps once, keeps its map in flash over
 * a reboot and localizes in it afterwards (issue 31, item 6). One boot of
 * it is rsm_mapflash_boot, the same source on the target (mapflash_target.c:
 * a region of the emulated board kept over a system reset) and on the host
 * (mapflash_host.c: an array, two boots in a row), so that the test can
 * compare the two (tests: m4.mapflash_reboots).
 *
 * A boot first tries to load the region. Refused (an erased or blank
 * region, or garbage): it maps the replay's scans 1 .. RSM_MAPFLASH_MAP_SCANS,
 * saves the map into the region and asks for a reset. Loaded: it localizes,
 * the map frozen, from the saved pose over the next RSM_MAPFLASH_LOC_SCANS
 * scans, as if the robot had stood still while it rebooted; then, as a robot
 * switched on somewhere in the mapped building, it sets the localizer up
 * again, loads the map again and searches it globally
 * (rsm_localizer_global: no pose) over the scans from
 * RSM_MAPFLASH_GLOBAL_FROM on until a pose is trusted, at most
 * RSM_MAPFLASH_GLOBAL_SCANS scans, each scan timed with the io's clock
 * (the target's: the global search's cost per scan on the M4).
 *
 * Output, one line each (floats as their IEEE bits in hexadecimal, as the
 * replay's, so that host and target compare bit for bit):
 *   F region <bytes> page <bytes>                 the flash region
 *   C <n1> <ticks1> <n2> <ticks2>                 the clock's check (calib.h),
 *                                                 the target only, before F
 *   L refused <status> <text>                     the load's refusal, first boot
 *   L loaded bytes <n> tiles <n> stamp <n> pose <x> <y> <theta>
 *   P <scan> <outcome> <x> <y> <theta>            pose after each scan
 *   S saved bytes <n> tiles <n> stamp <n> pose <x> <y> <theta>
 *   E scans <n> accepted <n> map_bytes <n>        after localizing
 *   G <scan> <outcome> <search_work> <cost>       each scan of the global search:
 *                                                 report.search_work, the clock's
 *                                                 ticks of rsm_localizer_scan (0
 *                                                 without a clock)
 *   GE proven <0|1> scans <n> budget <reads> pose <x> <y> <theta>
 *                                                 its end: a pose trusted (as rsm-nav's
 *                                                 first_trusted_scan) or not, after n
 *                                                 scans at global_budget reads a scan
 *                                                 at most, the last scan's pose
 * then "rsm mapflash: saved, resetting" or "rsm mapflash: done". */
#ifndef RSM_MAPFLASH_H
#define RSM_MAPFLASH_H

#include <stddef.h>
#include <stdint.h>

#include "replay.h"
#include "rsm/localizer.h"
#include "rsm/mapfile.h"
#include "rsm/scan.h"

/* Scans mapped on the first boot, and localized on the second: short runs
 * (each boot well under a second of host time under QEMU). The excerpt's
 * robot goes down a corridor; the localized scans stay where the mapped
 * ones saw. */
#ifndef RSM_MAPFLASH_MAP_SCANS
#define RSM_MAPFLASH_MAP_SCANS 350u
#endif
#ifndef RSM_MAPFLASH_LOC_SCANS
#define RSM_MAPFLASH_LOC_SCANS 100u
#endif
/* The global search's scans: from the localized run's first on (again),
 * at most this many; it proves a pose within a few (mapflash.c says why
 * not the scans after the localized run). */
#ifndef RSM_MAPFLASH_GLOBAL_FROM
#define RSM_MAPFLASH_GLOBAL_FROM (RSM_MAPFLASH_MAP_SCANS + 1u)
#endif
#ifndef RSM_MAPFLASH_GLOBAL_SCANS
#define RSM_MAPFLASH_GLOBAL_SCANS 100u
#endif

/* Flash as a NOR part behaves: erased to 0xFF a page at a time; a write
 * only clears bits (writing a 1 over a 0 fails, as programming an unerased
 * word would). */
#define RSM_MAPFLASH_PAGE 4096u
#define RSM_MAPFLASH_PAGES(bytes) (((bytes) + RSM_MAPFLASH_PAGE - 1u) / RSM_MAPFLASH_PAGE * RSM_MAPFLASH_PAGE)

/* The map larger than the pool (RSM_MAPFLASH_STORE 1: the rsm_mapstore
 * images, whose core is built with a pool smaller than the excerpt's map,
 * RSM_TMAP_TILES): mapping, the tiles the pool lets go are kept in a store
 * in RAM (rsm_tilestore_mem_t: external RAM on a real robot); the map is
 * saved whole, and the index of its tiles (rsm_tilestore_rom_build_index)
 * is programmed after it. Each later boot localizes on the map where it
 * lies, the flash store (rsm_tilestore_rom_t) serving from flash what the
 * pool does not hold: in RAM only the pool and a bit a tile. One more line:
 *   T store held <n> let_go <n> taken <n> lost <n>   after S and after E: the
 *                                                 store's tiles, and the map's
 *                                                 counters (rsm/tilestore.h) */
#ifndef RSM_MAPFLASH_STORE
#define RSM_MAPFLASH_STORE 0
#endif
#if RSM_MAPFLASH_STORE
#define RSM_MAPFLASH_NAME "rsm mapstore"
/* Tiles the RAM store holds while mapping. */
#ifndef RSM_MAPFLASH_STORE_TILES
#define RSM_MAPFLASH_STORE_TILES 1024u
#endif
/* Index words: 2^11, at least 4/3 of any map this build saves. */
#define RSM_MAPFLASH_INDEX_LOG2 11u
#define RSM_MAPFLASH_MAX_TILES ((uint32_t)RSM_TMAP_TILES + RSM_MAPFLASH_STORE_TILES)
#define RSM_MAPFLASH_INDEX_AT \
    RSM_MAPFLASH_PAGES(RSM_MAPFILE_HEADER_BYTES + RSM_MAPFLASH_MAX_TILES * RSM_MAPFILE_TILE_BYTES + 4u)
#define RSM_MAPFLASH_REGION RSM_MAPFLASH_PAGES(RSM_MAPFLASH_INDEX_AT + (4u << RSM_MAPFLASH_INDEX_LOG2))
#include "rsm/tilestore.h"
#else
#define RSM_MAPFLASH_NAME "rsm mapflash"
#define RSM_MAPFLASH_REGION RSM_MAPFLASH_PAGES(RSM_MAPFILE_MAX_BYTES)
#endif

typedef struct rsm_mapflash_region {
    uint8_t *bytes; /* RSM_MAPFLASH_REGION of them, word-aligned (the index is read as words) */
    uint32_t size;
} rsm_mapflash_region_t;

/* The callbacks of rsm_localizer_save_map and _load_map, ctx a region. */
int rsm_mapflash_write(void *ctx, uint32_t offset, const uint8_t *buf, size_t len);
int rsm_mapflash_read(void *ctx, uint32_t offset, uint8_t *buf, size_t len);
/* Erases the pages that hold [0, len); RSM_OK or RSM_ERR_RANGE. */
int rsm_mapflash_erase(rsm_mapflash_region_t *r, uint32_t len);

/* Caller-owned state (static in the images; the library keeps none). */
typedef struct rsm_mapflash {
    rsm_localizer_config_t cfg; /* the localizer keeps a pointer to it */
    rsm_localizer_t loc;
    rsm_scan_t scan;
    rsm_localizer_report_t rep;
    rsm_mapfile_info_t info;
    uint8_t search[RSM_GLOBAL_LEND_BYTES]; /* the global search's grids */
#if RSM_MAPFLASH_STORE
    rsm_tile_store_t store;
    rsm_tilestore_mem_t mem; /* mapping */
    rsm_tile_t mem_tiles[RSM_MAPFLASH_STORE_TILES];
    uint32_t mem_index[1u << RSM_MAPFLASH_INDEX_LOG2];
    rsm_tilestore_rom_t rom; /* localizing: over the region */
    uint8_t rom_out[(RSM_MAPFLASH_MAX_TILES + 7u) / 8u];
#endif
} rsm_mapflash_t;

typedef enum rsm_mapflash_result {
    RSM_MAPFLASH_DONE = 0,  /* localized in the loaded map: stop */
    RSM_MAPFLASH_RESET = 1, /* mapped and saved: reboot now */
    RSM_MAPFLASH_FAILED = 2 /* a call failed (said on a FAULT line) */
} rsm_mapflash_result_t;

/* One boot, as above. */
rsm_mapflash_result_t rsm_mapflash_boot(rsm_mapflash_t *m, rsm_mapflash_region_t *flash, const rsm_replay_io_t *io);

#endif /* RSM_MAPFLASH_H */
