/* Every compile-time capacity of rsm, in one place.
 *
 * Each value can be overridden by defining it before this header is read,
 * most simply through a user header named at build time:
 *     -DRSM_USER_CONFIG=my_rsm_config.h
 * which is included first. Capacities only bound memory; tuning values
 * (thresholds, noise, seeds) live in the runtime config structs of each
 * module. RAM costs below are for the state struct that holds the buffer. */
#ifndef RSM_CONFIG_H
#define RSM_CONFIG_H

#define RSM_STRINGIFY_(x) #x
#define RSM_STRINGIFY(x) RSM_STRINGIFY_(x)

#ifdef RSM_USER_CONFIG
#include RSM_STRINGIFY(RSM_USER_CONFIG)
#endif

/* ---- scans ------------------------------------------------------------ */

/* Readings per scan the core accepts (LMS: 181 or 361; CARMEN logs: 180;
 * one LMS 0xB0 telegram carries at most 401). 8 bytes each in a scan. */
#ifndef RSM_MAX_BEAMS
#define RSM_MAX_BEAMS 361
#endif

/* ---- image and map ---------------------------------------------------- */

/* log2 of the side, in cells, of the square scrolling map and of the scan
 * image drawn in the same frame. 7 -> 128 x 128 cells (6.4 m at 5 cm).
 * Map: 1 byte per cell; scan image: 1 bit per cell. */
#ifndef RSM_MAP_SIZE_LOG2
#define RSM_MAP_SIZE_LOG2 7
#endif

/* Set cells listed per scan image (work and clearing follow this list;
 * extra cells are still drawn). 4 bytes each. */
#ifndef RSM_IMAGE_MAX_CELLS
#define RSM_IMAGE_MAX_CELLS (2 * RSM_MAX_BEAMS)
#endif

/* ---- persistent map (tilemap.h) ---------------------------------------- */

/* log2 of a map tile's side in cells: 3 -> 8 x 8 cells (0.4 m at the
 * default 5 cm). 4 bits per cell: 32 bytes a tile plus 8 of header. Small
 * tiles waste less on space without walls (docs/map.md). */
#ifndef RSM_TMAP_TILE_LOG2
#define RSM_TMAP_TILE_LOG2 3
#endif

/* Default side of the finest cells, metres (the runtime default of
 * rsm_tmap_config_t.cell_m): a smaller pool holds a building better with
 * coarser cells (rsm/config_small.h). */
#ifndef RSM_TMAP_CELL_M
#define RSM_TMAP_CELL_M 0.05f
#endif

/* Resolutions the map keeps (cells of 1, 2, 4, ... times the finest). */
#ifndef RSM_TMAP_LEVELS
#define RSM_TMAP_LEVELS 4
#endif

/* Tiles in the pool, all levels together: 40 bytes each at 8 x 8 cells.
 * When it is full the least recently written tile is reused: with 2600
 * the 5 cm level follows the robot while the coarser ones keep most of a
 * building (docs/map.md). */
#ifndef RSM_TMAP_TILES
#define RSM_TMAP_TILES 2600
#endif

/* log2 of the tile index's slots (2 bytes each); at least 4/3 of the
 * tiles, so that linear probing stays short. */
#ifndef RSM_TMAP_HASH_LOG2
#define RSM_TMAP_HASH_LOG2 12
#endif

/* log2 of the bits that remember where the last map write's returns were
 * (rsm_tmap_config_t.wall_echo, docs/map.md): 2^14 bits = 2 KiB hold a
 * scan's few hundred cells with few collisions. */
#ifndef RSM_TMAP_ECHO_LOG2
#define RSM_TMAP_ECHO_LOG2 14
#endif

/* Oldest tiles one search of the full pool remembers for the evictions
 * that follow in the same map write (6 bytes each): a search reads every
 * tile, and a write into new ground evicts tens of them. */
#ifndef RSM_TMAP_VICTIMS
#define RSM_TMAP_VICTIMS 16
#endif

/* Tiles a read cursor holds per axis (a power of two; the cursor, on the
 * stack, holds its square at 8 bytes each): with 4, the tiles the last
 * beams crossed near the laser are found again without the index. */
#ifndef RSM_TMAP_CURSOR_WAYS
#define RSM_TMAP_CURSOR_WAYS 4
#endif

/* ---- global search (rsm_localizer_global) ----------------------------- */

/* Memory of the global search's bound grids: about 1.34 bytes times the
 * square of this, or the RSM_MAX_BEAMS x 8 bytes of the scan a map write
 * reads (whose memory they share) when that is more: 2 888 bytes by
 * default, whose finest grid has its blocks 0.4 m apart over the Intel map
 * (40 m wide at 0.2 m cells), 0.8 m over ACES (59 m). A wider map gets
 * blocks farther apart (slower bounds). 76 (about 8 KiB) read 20 % fewer
 * on Intel and 60 % fewer on ACES (docs/globalsearch.md). */
#ifndef RSM_GLOBAL_SIDE
#define RSM_GLOBAL_SIDE 40
#endif

/* Readings of the scan a global search scores poses with: fewer is faster
 * and more easily fooled (the proof descends with twice as many). 32 found
 * the same poses as 48 on the Intel log with 0.6 times the reads; 24 and
 * 28 read more (docs/globalsearch.md). 16 bytes each. */
#ifndef RSM_GLOBAL_POINTS
#define RSM_GLOBAL_POINTS 32
#endif

/* Distinct poses a global search keeps for its final test. 16 bytes each. */
#ifndef RSM_GLOBAL_CANDIDATES
#define RSM_GLOBAL_CANDIDATES 8
#endif

/* The global search's headings are spaced so that the scan's far points
 * move this many cells of its level (0.2 m) from one to the next: each
 * heading costs a whole branch and bound. At 2, with 32 readings and 8
 * kept poses, starts and kidnaps were found about 1.6 times sooner on the
 * Intel and ACES maps and no more poses went wrong (300 starts a log); with
 * the small preset's 24 readings and 4 kept poses, 2 proved look-alikes
 * (docs/globalsearch.md, "Half the headings"). */
#ifndef RSM_GLOBAL_HEADING_CELLS
#define RSM_GLOBAL_HEADING_CELLS 2
#endif

/* Searches of the whole map at the global search's first bar (0.97), each
 * from a new scan, before the bar falls to 0.95. A first search that keeps
 * no pose mostly missed the robot's place by a reading or two (a person,
 * clutter near the laser), and a search at 0.97 from the next scan reads
 * about half of what one at 0.95 does. At 2, over 300 starts a log, held
 * starts right within 20 scans went from 262 to 264 on the Intel map and
 * from 140 to 147 on ACES, with no new wrong pose; the small preset's
 * weaker searches were not measured so and keep 1 (docs/globalsearch.md,
 * "The first bar twice"). A search near the estimate (rsm_localizer_global_near)
 * searches each window at 0.97 once, as before. */
#ifndef RSM_GLOBAL_FIRST_SEARCHES
#define RSM_GLOBAL_FIRST_SEARCHES 2
#endif

/* Searches of the whole map at each of the global search's bars below the
 * first (0.95, 0.90, 0.85), each from a new scan, before the bar falls: a
 * lower bar reads several times as much, and a scan whose reading a person
 * hides fails where the next may not. At 3, with 32 readings and 8 kept
 * poses, starts and kidnaps that took several searches were found sooner
 * on the Intel and ACES maps; with the small preset's 24 readings and 4
 * kept poses, the searches repeated proved more look-alikes
 * (docs/globalsearch.md, "Each bar three times"). */
#ifndef RSM_GLOBAL_BAR_SEARCHES
#define RSM_GLOBAL_BAR_SEARCHES 3
#endif

/* RSM_GLOBAL_LEND_BYTES: the memory rsm-nav and the map-in-flash images
 * lend the global search's grids (rsm_localizer_set_search_memory),
 * outside the localizer's state: about 0.6 times the reads of the 2 888
 * shared bytes on the Intel log (docs/globalsearch.md). The library uses
 * what it is lent, or the shared bytes without. By default 24576 bytes, or
 * the grids' shared bytes where those are more (a larger RSM_MAX_BEAMS or
 * RSM_GLOBAL_SIDE), set beside them in rsm/localizer_parts.h; a value
 * given here that cannot hold them stops the build. On an STM32F407 the
 * default fits the core-coupled RAM beside the stack
 * (docs/bringup-stm32f4.md). */

/* ---- key points and matches ------------------------------------------- */

/* Harris key points kept per image (strongest first). 8 bytes each. */
#ifndef RSM_MAX_KEYPOINTS
#define RSM_MAX_KEYPOINTS 64
#endif

/* Harris candidates examined per image before the strongest are kept
 * (occupied cells near the scan). 8 bytes each, in the detector's
 * caller-owned workspace. */
#ifndef RSM_MAX_CANDIDATES
#define RSM_MAX_CANDIDATES 768
#endif

/* Tentative correspondences between reference and current key points.
 * 4 bytes each. */
#ifndef RSM_MAX_MATCHES
#define RSM_MAX_MATCHES 192
#endif

/* ---- ICP baseline ------------------------------------------------------ */

/* Points in each ICP point set (reference and current). 8 bytes each. */
#ifndef RSM_ICP_MAX_POINTS
#define RSM_ICP_MAX_POINTS RSM_MAX_BEAMS
#endif

/* ---- serial protocols -------------------------------------------------- */

/* Largest ARIA packet on the wire: 3 header bytes + a byte count of 255. */
#ifndef RSM_ARIA_MAX_PACKET
#define RSM_ARIA_MAX_PACKET 258
#endif

/* Sonar readings kept from one SIP (disc numbers are 0..31). Readings past
 * this count are still skipped correctly, only not stored. 3 bytes each. */
#ifndef RSM_ARIA_MAX_SONAR
#define RSM_ARIA_MAX_SONAR 32
#endif

/* Size, NUL included, of every decoded ARIA string (robot name, class,
 * subclass, CONFIG strings). Longer strings are cut and flagged. */
#ifndef RSM_ARIA_STR_SIZE
#define RSM_ARIA_STR_SIZE 32
#endif

/* Largest SICK LMS 2xx telegram accepted on the wire (0xB0 with 401 values
 * is 812 bytes; optional index bytes add a few). */
#ifndef RSM_LMS_MAX_TELEGRAM
#define RSM_LMS_MAX_TELEGRAM 820
#endif

/* ---- drivers ----------------------------------------------------------- */

/* Bytes one driver poll reads from its link at most (the receive chunk in
 * rsm_link_rx_t, one per driver). Larger chunks mean fewer reads for the
 * same traffic; any size >= 1 is correct, since the codecs take bytes in
 * pieces of any size. */
#ifndef RSM_LINK_RX_CHUNK
#define RSM_LINK_RX_CHUNK 128
#endif

/* ---- time alignment (sync.h) ----------------------------------------- */

/* Encoder samples the odometry/scan aligner holds back so that a scan
 * stamped before they arrived (a telegram still on the wire) is fused with
 * odometry interpolated at its own time. 16 bytes each; at the P3-DX's
 * 10 Hz, 16 covers 1.6 s of latency. */
#ifndef RSM_SYNC_DEPTH
#define RSM_SYNC_DEPTH 16
#endif

/* ---- spinning lidars (revolution.h) ------------------------------------ */

/* Odometry poses the revolution assembler keeps to place every point of a
 * turn at the pose the robot had when it was measured (de-skew). 24 bytes
 * each; at 50 Hz odometry, 32 cover 0.64 s, three turns of a 5 Hz lidar:
 * enough for a turn and the wait for odometry after it (a turn whose first
 * pose would be dropped while it waits is de-skewed then). The assembler
 * also keeps two turns of points, 12 bytes per RSM_MAX_BEAMS each. */
#ifndef RSM_REV_ODOM_DEPTH
#define RSM_REV_ODOM_DEPTH 32
#endif

/* ---- arithmetic of the map matcher ------------------------------------ */

/* 1: the map matcher's reads and sums in fixed point (32-bit integers,
 * 64-bit sums) instead of float. Without an FPU every float operation is a
 * call into the compiler's library, and the matcher's ~45 of them per map
 * read were most of a scan; in fixed point a Cortex-M3's scan costs about
 * 40 % of the instructions. The results differ from the float build's in the last
 * bits, so the trajectory is this build's own (within the float build's
 * accuracy: docs/fpu-less.md), and the host replay a soft-float image is
 * compared with must be built with the same value. Defaults to 1 exactly
 * where the library's soft-float shortcuts are on (an Arm core without an
 * FPU: src/core/compiler.h's RSM_SOFT_FLOAT), 0 with an FPU. Part of the
 * fingerprint below. */
#ifndef RSM_FIXED_MATCH
#if defined(__arm__) && !defined(__ARM_FP)
#define RSM_FIXED_MATCH 1
#else
#define RSM_FIXED_MATCH 0
#endif
#endif

/* ---- derived values and compile-time checks ---------------------------- */

#define RSM_MAP_SIZE (1 << RSM_MAP_SIZE_LOG2)
#define RSM_MAP_CELLS (RSM_MAP_SIZE * RSM_MAP_SIZE)

/* C99 static assertion: a negative array size stops the build. */
#define RSM_STATIC_ASSERT(name, cond) typedef char rsm_static_assert_##name[(cond) ? 1 : -1]

RSM_STATIC_ASSERT(max_beams_positive, RSM_MAX_BEAMS >= 2);
RSM_STATIC_ASSERT(max_beams_fits_lms, RSM_MAX_BEAMS <= 4096);
RSM_STATIC_ASSERT(map_size_range, RSM_MAP_SIZE_LOG2 >= 4 && RSM_MAP_SIZE_LOG2 <= 12);
RSM_STATIC_ASSERT(keypoints_fit_grid, RSM_MAX_KEYPOINTS >= 2 && RSM_MAX_KEYPOINTS <= RSM_MAP_CELLS);
RSM_STATIC_ASSERT(candidates_hold_keypoints, RSM_MAX_CANDIDATES >= RSM_MAX_KEYPOINTS);
RSM_STATIC_ASSERT(matches_positive, RSM_MAX_MATCHES >= 2);
RSM_STATIC_ASSERT(image_cells_positive, RSM_IMAGE_MAX_CELLS >= RSM_MAX_BEAMS);
RSM_STATIC_ASSERT(tmap_tile_range, RSM_TMAP_TILE_LOG2 >= 2 && RSM_TMAP_TILE_LOG2 <= 7);
RSM_STATIC_ASSERT(tmap_levels_range, RSM_TMAP_LEVELS >= 1 && RSM_TMAP_LEVELS <= 4);
RSM_STATIC_ASSERT(tmap_tiles_range, RSM_TMAP_TILES >= 4 && RSM_TMAP_TILES < 65535);
RSM_STATIC_ASSERT(tmap_echo_range, RSM_TMAP_ECHO_LOG2 >= 6 && RSM_TMAP_ECHO_LOG2 <= 20);
RSM_STATIC_ASSERT(tmap_victims_range, RSM_TMAP_VICTIMS >= 1 && RSM_TMAP_VICTIMS <= 1024);
RSM_STATIC_ASSERT(tmap_cursor_ways_pow2, RSM_TMAP_CURSOR_WAYS >= 2 && RSM_TMAP_CURSOR_WAYS <= 16 &&
                                             (RSM_TMAP_CURSOR_WAYS & (RSM_TMAP_CURSOR_WAYS - 1)) == 0);
RSM_STATIC_ASSERT(tmap_hash_room, RSM_TMAP_HASH_LOG2 <= 16 && (1L << RSM_TMAP_HASH_LOG2) * 3L >= 4L * RSM_TMAP_TILES);
RSM_STATIC_ASSERT(global_side_range, RSM_GLOBAL_SIDE >= 4 && RSM_GLOBAL_SIDE <= 1024);
RSM_STATIC_ASSERT(global_points_range, RSM_GLOBAL_POINTS >= 8 && RSM_GLOBAL_POINTS <= 1024);
RSM_STATIC_ASSERT(global_candidates_range, RSM_GLOBAL_CANDIDATES >= 2 && RSM_GLOBAL_CANDIDATES <= 64);
RSM_STATIC_ASSERT(global_heading_cells_range, RSM_GLOBAL_HEADING_CELLS >= 1 && RSM_GLOBAL_HEADING_CELLS <= 4);
RSM_STATIC_ASSERT(global_bar_searches_range, RSM_GLOBAL_BAR_SEARCHES >= 1 && RSM_GLOBAL_BAR_SEARCHES <= 8);
RSM_STATIC_ASSERT(global_first_searches_range, RSM_GLOBAL_FIRST_SEARCHES >= 1 && RSM_GLOBAL_FIRST_SEARCHES <= 8);
RSM_STATIC_ASSERT(aria_packet_size, RSM_ARIA_MAX_PACKET >= 258);
RSM_STATIC_ASSERT(aria_sonar_range, RSM_ARIA_MAX_SONAR >= 1 && RSM_ARIA_MAX_SONAR <= 255);
RSM_STATIC_ASSERT(aria_str_size, RSM_ARIA_STR_SIZE >= 8 && RSM_ARIA_STR_SIZE <= 256);
RSM_STATIC_ASSERT(lms_telegram_size, RSM_LMS_MAX_TELEGRAM >= 812);
RSM_STATIC_ASSERT(link_rx_chunk_range, RSM_LINK_RX_CHUNK >= 1 && RSM_LINK_RX_CHUNK <= 65536);
RSM_STATIC_ASSERT(sync_depth_range, RSM_SYNC_DEPTH >= 2 && RSM_SYNC_DEPTH <= 1024);
RSM_STATIC_ASSERT(rev_odom_depth_range, RSM_REV_ODOM_DEPTH >= 2 && RSM_REV_ODOM_DEPTH <= 1024);
RSM_STATIC_ASSERT(fixed_match_bool, RSM_FIXED_MATCH == 0 || RSM_FIXED_MATCH == 1);

/* A digest of every capacity above (FNV-1a over their values), as the code
 * including this header sees them. The library compares the caller's with
 * its own (rsm_localizer_init), so that an application compiled with other
 * capacities than the library gets RSM_ERR_CONFIG instead of a state object
 * of the wrong size. RSM_CONFIG_FINGERPRINT mixes RSM_FIXED_MATCH in too, but
 * only when it is 1 (the float build's digest is the one it always was): a
 * caller that expects the other arithmetic's trajectories is told so. Map
 * files carry the capacities' digest alone: the fixed-point and the float
 * builds read and write the same maps. */
#define RSM_CONFIG_MIX_(h, v) ((((unsigned long)(h) ^ (unsigned long)(v)) * 16777619ul) & 0xFFFFFFFFul)
#define RSM_CONFIG_CAPACITY_FINGERPRINT                                                                             \
    RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_( \
    RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_( \
    RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(RSM_CONFIG_MIX_(2166136261ul, RSM_MAX_BEAMS), RSM_MAP_SIZE_LOG2),                  \
    RSM_IMAGE_MAX_CELLS), RSM_TMAP_TILE_LOG2), RSM_TMAP_LEVELS), RSM_TMAP_TILES), RSM_TMAP_HASH_LOG2), RSM_TMAP_ECHO_LOG2), \
    RSM_MAX_KEYPOINTS), RSM_MAX_CANDIDATES), RSM_MAX_MATCHES), RSM_ICP_MAX_POINTS), RSM_ARIA_MAX_PACKET),             \
    RSM_ARIA_MAX_SONAR), RSM_ARIA_STR_SIZE), RSM_LMS_MAX_TELEGRAM), RSM_LINK_RX_CHUNK), RSM_SYNC_DEPTH),          \
    RSM_REV_ODOM_DEPTH), RSM_TMAP_VICTIMS), RSM_GLOBAL_SIDE), RSM_GLOBAL_POINTS), RSM_GLOBAL_CANDIDATES)
#if RSM_FIXED_MATCH
#define RSM_CONFIG_FINGERPRINT RSM_CONFIG_MIX_(RSM_CONFIG_CAPACITY_FINGERPRINT, 0x46495844ul) /* "FIXD" */
#else
#define RSM_CONFIG_FINGERPRINT RSM_CONFIG_CAPACITY_FINGERPRINT
#endif

#endif /* RSM_CONFIG_H */
