/* Saving and loading the persistent map (issue 31, item 1): a round trip
 * gives the same map bit for bit and the same run afterwards; every
 * single-bit flip and every truncation of a saved map is refused with the
 * localizer as it was; maps of another build, cell size or version are
 * refused; a failing writer is reported. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "rsm/config.h"
#include "rsm/localizer.h"
#include "rsm/mapfile.h"
#include "rsm/status.h"
#include "synth.h"
#include "map/tilemap.h"
#include "unity.h"

#define STEP_US 100000u
#define PATH_CAP 400u

static rsm_localizer_t loc;
static rsm_localizer_t other;
static rsm_localizer_t before;
static rsm_localizer_t mapper;
static rsm_localizer_config_t cfg;
static rsm_synth_scan_config_t scan_cfg;
static rsm_scan_t scan;
static rsm_pose_t path[PATH_CAP];
static size_t path_len;
static rsm_pose_t track_a[PATH_CAP];
static rsm_pose_t track_b[PATH_CAP];
static rsm_pose_t track_m[PATH_CAP];

/* Storage: a RAM region the callbacks read and write, of a given length
 * (reads past it fail: a truncated map), whose writes can fail from the
 * n-th on. */
typedef struct store {
    uint8_t bytes[RSM_MAPFILE_MAX_BYTES];
    uint32_t len;
    uint32_t writes;
    uint32_t fail_from; /* 0: never */
    uint32_t reads;
} store_t;

static store_t store;
static store_t copy;

static int store_write(void *ctx, uint32_t offset, const uint8_t *buf, size_t len)
{
    store_t *s = (store_t *)ctx;
    s->writes++;
    if ((s->fail_from != 0u && s->writes >= s->fail_from) || offset > sizeof s->bytes ||
        len > sizeof s->bytes - offset) {
        return -1;
    }
    memcpy(s->bytes + offset, buf, len);
    if (offset + len > s->len) {
        s->len = (uint32_t)(offset + len);
    }
    return 0;
}

static int store_read(void *ctx, uint32_t offset, uint8_t *buf, size_t len)
{
    store_t *s = (store_t *)ctx;
    s->reads++;
    if (offset > s->len || len > s->len - offset) {
        return -1;
    }
    memcpy(buf, s->bytes + offset, len);
    return 0;
}

void setUp(void)
{
    cfg = rsm_localizer_config_default();
    scan_cfg = rsm_synth_scan_config_default();
    memset(&store, 0, sizeof store);
}

void tearDown(void)
{
}

/* The room world, a tour through it; the first `scans` poses of it mapped
 * by loc with exact odometry. */
static void map_room(size_t scans)
{
    static const rsm_synth_leg_t legs[] = {{1.0f, 0.0f}, {0.0f, 1.2f}, {0.6f, 0.0f}, {0.0f, -2.4f}, {1.2f, 0.3f}};
    const rsm_pose_t start = {-1.2f, -0.8f, 0.0f};
    const rsm_synth_world_t world = rsm_synth_world_room();
    size_t k;
    path_len = rsm_synth_path(&start, legs, sizeof legs / sizeof legs[0], 0.05f, 0.05f, path, PATH_CAP);
    TEST_ASSERT_TRUE(path_len > 40u);
    TEST_ASSERT_TRUE(scans <= path_len);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &cfg, &path[0], NULL));
    for (k = 0; k < scans; ++k) {
        if (k > 0u) {
            const rsm_motion_t u = rsm_synth_motion(&path[k - 1u], &path[k], NULL);
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_motion(&loc, &u));
        }
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_synth_scan(&world, &path[k], &scan_cfg, NULL, (uint64_t)k * STEP_US, &scan));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(&loc, &scan, NULL));
    }
}

/* Runs l over path[from, path_len) with exact odometry from path[from - 1]. */
static void run_on(rsm_localizer_t *l, size_t from, rsm_pose_t *track)
{
    const rsm_synth_world_t world = rsm_synth_world_room();
    size_t k;
    for (k = from; k < path_len; ++k) {
        const rsm_motion_t u = rsm_synth_motion(&path[k - 1u], &path[k], NULL);
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_motion(l, &u));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_synth_scan(&world, &path[k], &scan_cfg, NULL, (uint64_t)k * STEP_US, &scan));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(l, &scan, NULL));
        track[k] = rsm_localizer_pose(l);
    }
}

/* Where the mapper itself, carrying on from scan `at`, puts the rest of the
 * path: the map's frame, which a localizer on the saved map must agree
 * with (its drift from the truth is the map's own). */
static void mapper_track(size_t at)
{
    mapper = loc;
    run_on(&mapper, at, track_m);
}

static void assert_near_mapper(const rsm_pose_t *track, size_t at)
{
    size_t k;
    for (k = at; k < path_len; ++k) {
        TEST_ASSERT_TRUE(rsm_synth_pos_error(&track[k], &track_m[k]) < 0.03f);
        TEST_ASSERT_TRUE(rsm_synth_angle_error(&track[k], &track_m[k]) < 0.02f);
    }
}

static const rsm_tmap_t *map_of(const rsm_localizer_t *l)
{
    return &l->state.persistent.map;
}

/* The same map: the same tiles in the same slots, the same counts and
 * write counter. */
static void assert_same_map(const rsm_tmap_t *a, const rsm_tmap_t *b)
{
    TEST_ASSERT_EQUAL_UINT32(a->used, b->used);
    TEST_ASSERT_EQUAL_UINT32(a->stamp, b->stamp);
    TEST_ASSERT_EQUAL_MEMORY(a->level_used, b->level_used, sizeof a->level_used);
    TEST_ASSERT_EQUAL_MEMORY(a->tile, b->tile, (size_t)a->used * sizeof a->tile[0]);
}

static void test_round_trip_is_bit_for_bit(void)
{
    rsm_mapfile_info_t saved;
    rsm_mapfile_info_t loaded;
    map_room(60u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_save_map(&loc, store_write, &store, &saved));
    TEST_ASSERT_EQUAL_UINT32(store.len, saved.bytes);
    TEST_ASSERT_EQUAL_UINT32(rsm_localizer_map_bytes(&loc), saved.bytes);
    TEST_ASSERT_EQUAL_UINT32(map_of(&loc)->used, saved.tiles);
    TEST_ASSERT_TRUE(saved.tiles > 10u);
    /* At most the map's share of the state. */
    TEST_ASSERT_TRUE(saved.bytes <= sizeof(rsm_tmap_t));
    TEST_ASSERT_EQUAL_MEMORY(&loc.ekf.x, &saved.pose, sizeof saved.pose);

    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&other, &cfg, &path[0], NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_load_map(&other, store_read, &store, &loaded));
    TEST_ASSERT_EQUAL_MEMORY(&saved, &loaded, sizeof saved);
    assert_same_map(map_of(&loc), map_of(&other));
    /* The global search's grids are built with the load, for the map as
     * loaded. */
    TEST_ASSERT_EQUAL_UINT32(1u, other.state.persistent.global.cached);
    TEST_ASSERT_EQUAL_UINT32(map_of(&other)->counters.updates, other.state.persistent.global.cache_writes);
    {
        /* The tiles of the level searched (the grids' key holds that
         * level alone). */
        const rsm_tmap_t *m = map_of(&other);
        const uint32_t searched = (uint32_t)m->cfg.levels - 2u;
        TEST_ASSERT_TRUE(m->level_used[searched] > 0u);
        TEST_ASSERT_EQUAL_UINT32((uint32_t)m->level_used[searched], other.state.persistent.global.cache_tiles);
    }
    /* Every cell reads the same through the index too. */
    {
        int32_t x0;
        int32_t y0;
        int32_t x1;
        int32_t y1;
        int32_t gx;
        int32_t gy;
        TEST_ASSERT_EQUAL_INT(1, rsm_tmap_bounds(map_of(&loc), 0u, &x0, &y0, &x1, &y1));
        for (gy = y0; gy <= y1; ++gy) {
            for (gx = x0; gx <= x1; ++gx) {
                TEST_ASSERT_EQUAL_UINT8(rsm_tmap_value(map_of(&loc), 0u, gx, gy),
                                        rsm_tmap_value(map_of(&other), 0u, gx, gy));
            }
        }
    }
    /* Saved again, the same bytes. */
    copy = store;
    memset(&store, 0, sizeof store);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_set_pose(&other, &saved.pose, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_save_map(&other, store_write, &store, NULL));
    TEST_ASSERT_EQUAL_UINT32(copy.len, store.len);
    TEST_ASSERT_EQUAL_MEMORY(copy.bytes, store.bytes, copy.len);
}

/* The run after a load is the run on the map saved: a localizer given the
 * saved map and one that kept the mapper's map itself (the same
 * continuation state as a load sets) follow the same trajectory, bit for
 * bit; and both stay on the true path. */
static void test_run_after_load_is_the_same(void)
{
    const size_t at = 60u;
    map_room(at);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_save_map(&loc, store_write, &store, NULL));
    /* The mapper's map, its write finished as a load would find it. */
    while (rsm_tmap_write_run(&loc.state.persistent.map, loc.frame.world, 0u) != 0) {
    }
    memset(&store, 0, sizeof store);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_save_map(&loc, store_write, &store, NULL));

    /* Resumed where the mapper was. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&other, &cfg, &loc.ekf.x, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_load_map(&other, store_read, &store, NULL));
    before = other;
    memset(&before.state.persistent.map, 0, sizeof before.state.persistent.map);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_init(&before.state.persistent.map, &cfg.tmap));
    {
        rsm_tmap_t *m = &before.state.persistent.map;
        const rsm_tmap_t *src = map_of(&loc);
        uint32_t s;
        m->stamp = src->stamp;
        /* The continuation a load sets writes at a loaded map's rate. */
        m->write_hit = cfg.map_loaded_hit;
        for (s = 0; s < src->used; ++s) {
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_restore(m, &src->tile[s]));
        }
    }
    run_on(&other, at, track_a);
    run_on(&before, at, track_b);
    TEST_ASSERT_EQUAL_MEMORY(&track_a[at], &track_b[at], (path_len - at) * sizeof track_a[0]);
    mapper_track(at);
    assert_near_mapper(track_a, at);
}

/* Localization mode: a frozen map is matched, never written. */
static void test_frozen_map_is_never_written(void)
{
    const size_t at = 60u;
    map_room(at);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_save_map(&loc, store_write, &store, NULL));
    cfg.map_frozen = 1u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&other, &cfg, &loc.ekf.x, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_load_map(&other, store_read, &store, NULL));
    before = other;
    run_on(&other, at, track_a);
    assert_same_map(map_of(&before), map_of(&other));
    TEST_ASSERT_EQUAL_UINT32(0u, map_of(&other)->counters.updates);
    mapper_track(at);
    assert_near_mapper(track_a, at);
    /* Unfrozen, the same run writes. */
    cfg.map_frozen = 0u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&other, &cfg, &path[at - 1u], NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_load_map(&other, store_read, &store, NULL));
    run_on(&other, at, track_b);
    TEST_ASSERT_TRUE(map_of(&other)->counters.updates > 0u);
}

/* With updates on, a loaded map learns what changed at its own rate
 * (map_loaded_hit): a new wall comes into it, more slowly than into the
 * map of the run that made it (tmap.hit_inc), and both runs stay on the
 * path. */
static void test_a_loaded_map_learns_a_change_at_its_own_rate(void)
{
    /* The room with a new wall, 0.5 m long, in its south-east part, where
     * the rest of the path looks. */
    static rsm_synth_segment_t seg[64];
    const rsm_synth_segment_t added = {1.3f, -1.1f, 1.3f, -0.6f};
    const rsm_synth_world_t room = rsm_synth_world_room();
    const size_t at = 60u;
    rsm_synth_world_t changed;
    uint32_t learnt[2] = {0u, 0u};
    int r;
    size_t k;
    TEST_ASSERT_TRUE(room.count < sizeof seg / sizeof seg[0]);
    memcpy(seg, room.seg, room.count * sizeof seg[0]);
    seg[room.count] = added;
    changed.seg = seg;
    changed.count = room.count + 1u;
    map_room(at);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_save_map(&loc, store_write, &store, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&other, &cfg, &loc.ekf.x, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_load_map(&other, store_read, &store, NULL));
    mapper = loc;
    for (r = 0; r < 2; ++r) {
        rsm_localizer_t *l = r == 0 ? &mapper : &other;
        const rsm_tmap_t *m = map_of(l);
        const float inv = 1.0f / m->cfg.cell_m;
        for (k = at; k < path_len; ++k) {
            const rsm_motion_t u = rsm_synth_motion(&path[k - 1u], &path[k], NULL);
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_motion(l, &u));
            TEST_ASSERT_EQUAL_INT(RSM_OK,
                                  rsm_synth_scan(&changed, &path[k], &scan_cfg, NULL, (uint64_t)k * STEP_US, &scan));
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(l, &scan, NULL));
            (r == 0 ? track_m : track_a)[k] = rsm_localizer_pose(l);
        }
        /* The finest cells along the new wall, either side of it. */
        for (k = 0; k <= 20u; ++k) {
            const float y = added.y0 + (added.y1 - added.y0) * (float)k / 20.0f;
            const int32_t gy = (int32_t)floorf(y * inv);
            learnt[r] += rsm_tmap_value(m, 0u, (int32_t)floorf((added.x0 - 0.01f) * inv), gy);
            learnt[r] += rsm_tmap_value(m, 0u, (int32_t)floorf((added.x0 + 0.01f) * inv), gy);
        }
    }
    TEST_ASSERT_EQUAL_UINT8(1u, map_of(&other)->write_hit);
    TEST_ASSERT_EQUAL_UINT8(cfg.tmap.hit_inc, map_of(&mapper)->write_hit);
    TEST_ASSERT_TRUE(learnt[1] > 0u);
    TEST_ASSERT_TRUE(learnt[1] < learnt[0]);
    assert_near_mapper(track_a, at);
}

/* A localizer that holds a map of its own, to show that a refused load
 * leaves it as it was. */
static void prepare_victim(void)
{
    map_room(3u);
    other = loc;
    before = other;
}

static void assert_untouched(void)
{
    TEST_ASSERT_EQUAL_MEMORY(&before, &other, sizeof other);
}

static void test_every_bit_flip_is_refused(void)
{
    uint32_t bit;
    uint32_t refused = 0;
    /* A small map: the first scan's. */
    map_room(1u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_save_map(&loc, store_write, &store, NULL));
    TEST_ASSERT_TRUE(store.len < 16000u);
    copy = store;
    prepare_victim();
    for (bit = 0; bit < 8u * copy.len; ++bit) {
        int rc;
        store.bytes[bit / 8u] = (uint8_t)(copy.bytes[bit / 8u] ^ (1u << (bit % 8u)));
        rc = rsm_localizer_load_map(&other, store_read, &store, NULL);
        store.bytes[bit / 8u] = copy.bytes[bit / 8u];
        if (rc == RSM_ERR_CHECKSUM || rc == RSM_ERR_FORMAT || rc == RSM_ERR_IO) {
            refused++;
        }
        if (rc == RSM_OK) {
            TEST_FAIL_MESSAGE("a map with one bit flipped was taken");
        }
    }
    TEST_ASSERT_EQUAL_UINT32(8u * copy.len, refused);
    assert_untouched();
}

static void test_every_truncation_is_refused(void)
{
    uint32_t len;
    map_room(1u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_save_map(&loc, store_write, &store, NULL));
    copy = store;
    prepare_victim();
    for (len = 0; len < copy.len; ++len) {
        store.len = len;
        TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_localizer_load_map(&other, store_read, &store, NULL));
    }
    assert_untouched();
    /* Whole again, it loads. */
    store.len = copy.len;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_load_map(&other, store_read, &store, NULL));
}

/* Rewrites header byte `at` to v and the CRC to match: a map that is sound
 * as bytes but not one this build can take. */
static void forge(uint32_t at, uint8_t v)
{
    uint32_t crc;
    store = copy;
    store.bytes[at] = v;
    crc = rsm_crc32(0u, store.bytes, store.len - 4u);
    store.bytes[store.len - 4u] = (uint8_t)(crc & 0xFFu);
    store.bytes[store.len - 3u] = (uint8_t)((crc >> 8) & 0xFFu);
    store.bytes[store.len - 2u] = (uint8_t)((crc >> 16) & 0xFFu);
    store.bytes[store.len - 1u] = (uint8_t)(crc >> 24);
}

static void test_foreign_maps_are_refused(void)
{
    rsm_localizer_config_t coarse;
    /* Two levels, so that a tile can claim a level the map lacks. */
    cfg.tmap.levels = 2u;
    map_room(1u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_save_map(&loc, store_write, &store, NULL));
    copy = store;
    prepare_victim();
    forge(0u, (uint8_t)'X'); /* magic */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT, rsm_localizer_load_map(&other, store_read, &store, NULL));
    forge(4u, (uint8_t)(RSM_MAPFILE_VERSION + 1u)); /* version */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT, rsm_localizer_load_map(&other, store_read, &store, NULL));
    forge(8u, (uint8_t)(copy.bytes[8] ^ 0x01u)); /* another build's capacities */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT, rsm_localizer_load_map(&other, store_read, &store, NULL));
    forge(16u, (uint8_t)(copy.bytes[16] - 1u)); /* fewer levels */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT, rsm_localizer_load_map(&other, store_read, &store, NULL));
    forge(27u, 0x7Fu); /* more tiles than a pool holds */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT, rsm_localizer_load_map(&other, store_read, &store, NULL));
    /* A first tile of a level the map does not have, or written after the
     * map's last write. */
    forge(RSM_MAPFILE_HEADER_BYTES + 7u, (uint8_t)(copy.bytes[RSM_MAPFILE_HEADER_BYTES + 7u] | 0xC0u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT, rsm_localizer_load_map(&other, store_read, &store, NULL));
    forge(RSM_MAPFILE_HEADER_BYTES + 6u, 0x10u);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT, rsm_localizer_load_map(&other, store_read, &store, NULL));
    /* A first tile beyond the coordinates a map holds: the first pass,
     * which writes nothing, refuses it. */
    forge(RSM_MAPFILE_HEADER_BYTES + 1u, 0x7Fu);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT, rsm_localizer_load_map(&other, store_read, &store, NULL));
    forge(RSM_MAPFILE_HEADER_BYTES + 3u, 0x80u);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT, rsm_localizer_load_map(&other, store_read, &store, NULL));
    /* A pose that is not one (NaN x). */
    forge(35u, 0x7Fu);
    store.bytes[34] = 0xC0u;
    {
        const uint32_t crc = rsm_crc32(0u, store.bytes, store.len - 4u);
        store.bytes[store.len - 4u] = (uint8_t)(crc & 0xFFu);
        store.bytes[store.len - 3u] = (uint8_t)((crc >> 8) & 0xFFu);
        store.bytes[store.len - 2u] = (uint8_t)((crc >> 16) & 0xFFu);
        store.bytes[store.len - 1u] = (uint8_t)(crc >> 24);
    }
    TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT, rsm_localizer_load_map(&other, store_read, &store, NULL));
    assert_untouched();
    /* Another cell size in the loading configuration. */
    coarse = cfg;
    coarse.tmap.cell_m = 2.0f * cfg.tmap.cell_m;
    store = copy;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&other, &coarse, &path[0], NULL));
    before = other;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT, rsm_localizer_load_map(&other, store_read, &store, NULL));
    assert_untouched();
    TEST_ASSERT_EQUAL_STRING("not a map of this format, version or build", rsm_strerror(RSM_ERR_FORMAT));
}

/* A map that holds one place twice, its CRC made right: no save writes
 * one. The second pass finds it; the map is left empty, not half loaded. */
static void test_a_place_held_twice_is_refused(void)
{
    map_room(1u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_save_map(&loc, store_write, &store, NULL));
    copy = store;
    /* Tile 1 becomes a copy of tile 0. */
    memcpy(copy.bytes + RSM_MAPFILE_HEADER_BYTES + RSM_MAPFILE_TILE_BYTES, copy.bytes + RSM_MAPFILE_HEADER_BYTES,
           RSM_MAPFILE_TILE_BYTES);
    forge(0u, copy.bytes[0]);
    prepare_victim();
    TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT, rsm_localizer_load_map(&other, store_read, &store, NULL));
    TEST_ASSERT_EQUAL_UINT32(0u, map_of(&other)->used);
}

static void test_a_failing_writer_is_reported(void)
{
    uint32_t n;
    uint32_t calls;
    map_room(1u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_save_map(&loc, store_write, &store, NULL));
    calls = store.writes;
    TEST_ASSERT_EQUAL_UINT32(map_of(&loc)->used + 2u, calls);
    for (n = 1; n <= calls; ++n) {
        memset(&store, 0, sizeof store);
        store.fail_from = n;
        TEST_ASSERT_EQUAL_INT(RSM_ERR_IO, rsm_localizer_save_map(&loc, store_write, &store, NULL));
        TEST_ASSERT_EQUAL_UINT32(n, store.writes);
    }
}

static void test_bad_arguments(void)
{
    rsm_localizer_config_t icp = rsm_localizer_config_default();
    map_room(1u);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_save_map(NULL, store_write, &store, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_save_map(&loc, NULL, &store, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_load_map(NULL, store_read, &store, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_load_map(&loc, NULL, &store, NULL));
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_localizer_map_bytes(NULL));
    memset(&other, 0, sizeof other);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_save_map(&other, store_write, &store, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_load_map(&other, store_read, &store, NULL));
    icp.method = RSM_METHOD_ODOMETRY;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&other, &icp, &path[0], NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_localizer_save_map(&other, store_write, &store, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_localizer_load_map(&other, store_read, &store, NULL));
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_localizer_map_bytes(&other));
}

/* rsm_localizer_set_pose moves the estimate and refuses what is no pose. */
static void test_set_pose(void)
{
    const rsm_pose_t there = {0.5f, 0.25f, 1.0f};
    rsm_pose_t bad = there;
    const float p[9] = {0.01f, 0.0f, 0.0f, 0.0f, 0.01f, 0.0f, 0.0f, 0.0f, 0.001f};
    map_room(5u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_set_pose(&loc, &there, p));
    TEST_ASSERT_EQUAL_MEMORY(&there, &loc.ekf.x, sizeof there);
    TEST_ASSERT_EQUAL_MEMORY(p, loc.ekf.p, sizeof p);
    TEST_ASSERT_EQUAL_INT(RSM_TRACK_TRACKING, rsm_localizer_track(&loc));
    before = loc;
    bad.x = NAN;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_set_pose(&loc, &bad, p));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_set_pose(&loc, NULL, p));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_set_pose(NULL, &there, p));
    TEST_ASSERT_EQUAL_MEMORY(&before, &loc, sizeof loc);
}

static void test_crc32_check_value(void)
{
    /* The standard check value of CRC-32 over "123456789". */
    static const uint8_t digits[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
    TEST_ASSERT_EQUAL_HEX32(0xCBF43926u, rsm_crc32(0u, digits, sizeof digits));
    TEST_ASSERT_EQUAL_HEX32(0xCBF43926u, rsm_crc32(rsm_crc32(0u, digits, 4u), digits + 4, 5u));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_crc32_check_value);
    RUN_TEST(test_round_trip_is_bit_for_bit);
    RUN_TEST(test_run_after_load_is_the_same);
    RUN_TEST(test_frozen_map_is_never_written);
    RUN_TEST(test_a_loaded_map_learns_a_change_at_its_own_rate);
    RUN_TEST(test_every_bit_flip_is_refused);
    RUN_TEST(test_every_truncation_is_refused);
    RUN_TEST(test_foreign_maps_are_refused);
    RUN_TEST(test_a_place_held_twice_is_refused);
    RUN_TEST(test_a_failing_writer_is_reported);
    RUN_TEST(test_bad_arguments);
    RUN_TEST(test_set_pose);
    return UNITY_END();
}
