/* A store behind the map's pool (rsm/tilestore.h): the memory store keeps
 * what it is given and gives each tile back once; a map with a store lets
 * its oldest tiles go into it and takes them back when a scan needs them,
 * so that a map larger than the pool is kept whole; a saved map holds the
 * pool and the store, and loads back into both or is refused whole. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "rsm/config.h"
#include "rsm/localizer.h"
#include "rsm/mapfile.h"
#include "rsm/mapimport.h"
#include "rsm/status.h"
#include "rsm/tilestore.h"
#include "synth.h"
#include "map/tilemap.h"
#include "map/tmap_read.h"
#include "unity.h"

/* Room for the pool's worth twice over, and the store's index. */
#define STORE_TILES (2u * (uint32_t)RSM_TMAP_TILES + 64u > 4096u ? 2u * (uint32_t)RSM_TMAP_TILES + 64u : 4096u)
#define INDEX_LOG2 16u
#define STEP_US 100000u
#define PATH_CAP 400u

static rsm_tile_t tiles[STORE_TILES];
static uint32_t index_[1u << INDEX_LOG2];
static rsm_tilestore_mem_t mem;
static rsm_tile_store_t store;

static rsm_tile_t tiles2[STORE_TILES];
static uint32_t index2[1u << INDEX_LOG2];
static rsm_tilestore_mem_t mem2;
static rsm_tile_store_t store2;

static rsm_tmap_t map;
static rsm_localizer_t loc;
static rsm_localizer_t other;
static rsm_localizer_config_t cfg;
static rsm_scan_t scan;
static rsm_pose_t path[PATH_CAP];

/* A saved map in RAM. */
static uint8_t saved[RSM_MAPFILE_HEADER_BYTES + (3u * (uint32_t)RSM_TMAP_TILES + 64u) * RSM_MAPFILE_TILE_BYTES + 4u];
static uint32_t saved_len;

static int ram_write(void *ctx, uint32_t offset, const uint8_t *buf, size_t len)
{
    (void)ctx;
    if (offset > sizeof saved || len > sizeof saved - offset) {
        return -1;
    }
    memcpy(saved + offset, buf, len);
    if (offset + len > saved_len) {
        saved_len = (uint32_t)(offset + len);
    }
    return 0;
}

static int ram_read(void *ctx, uint32_t offset, uint8_t *buf, size_t len)
{
    (void)ctx;
    if (offset > saved_len || len > saved_len - offset) {
        return -1;
    }
    memcpy(buf, saved + offset, len);
    return 0;
}

void setUp(void)
{
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tilestore_mem_init(&mem, tiles, STORE_TILES, index_, INDEX_LOG2, &store));
    cfg = rsm_localizer_config_default();
    saved_len = 0u;
}

void tearDown(void)
{
}

static rsm_tile_t tile_at(uint32_t level, int32_t tx, int32_t ty, uint8_t fill)
{
    rsm_tile_t t;
    memset(&t, 0, sizeof t);
    t.tx = (int16_t)tx;
    t.ty = (int16_t)ty;
    t.stamp = (level << 30) | 7u;
    memset(t.cell, fill, sizeof t.cell);
    return t;
}

static void test_mem_store_should_refuse_bad_set_ups(void)
{
    rsm_tilestore_mem_t m;
    rsm_tile_store_t s;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tilestore_mem_init(NULL, tiles, 4u, index_, 4u, &s));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tilestore_mem_init(&m, NULL, 4u, index_, 4u, &s));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tilestore_mem_init(&m, tiles, 4u, NULL, 4u, &s));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tilestore_mem_init(&m, tiles, 4u, index_, 4u, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tilestore_mem_init(&m, tiles, 0u, index_, 4u, &s));
    /* An index too small for short probes. */
    TEST_ASSERT_EQUAL_UINT32(3u, rsm_tilestore_mem_index_log2(5u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tilestore_mem_init(&m, tiles, 7u, index_, 2u, &s));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tilestore_mem_init(&m, tiles, 7u, index_, 4u, &s));
    TEST_ASSERT_EQUAL_UINT32(7u, s.capacity);
}

static void test_mem_store_should_give_each_tile_back_once(void)
{
    rsm_tile_t a = tile_at(0u, 3, -4, 0x11u);
    rsm_tile_t b = tile_at(2u, 3, -4, 0x22u); /* the same place on another level */
    rsm_tile_t got;
    TEST_ASSERT_EQUAL_INT(RSM_OK, store.put(store.ctx, &a));
    TEST_ASSERT_EQUAL_INT(RSM_OK, store.put(store.ctx, &b));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT, store.put(store.ctx, &a));
    TEST_ASSERT_EQUAL_UINT32(2u, store.count(store.ctx));
    TEST_ASSERT_EQUAL_INT(0, store.take(store.ctx, 1u, 3, -4, &got));
    TEST_ASSERT_EQUAL_INT(1, store.take(store.ctx, 2u, 3, -4, &got));
    TEST_ASSERT_EQUAL_MEMORY(&b, &got, sizeof got);
    TEST_ASSERT_EQUAL_INT(0, store.take(store.ctx, 2u, 3, -4, &got));
    TEST_ASSERT_EQUAL_UINT32(1u, store.count(store.ctx));
    TEST_ASSERT_EQUAL_INT(RSM_OK, store.at(store.ctx, 0u, &got));
    TEST_ASSERT_EQUAL_MEMORY(&a, &got, sizeof got);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_RANGE, store.at(store.ctx, 1u, &got));
    store.clear(store.ctx);
    TEST_ASSERT_EQUAL_UINT32(0u, store.count(store.ctx));
    TEST_ASSERT_EQUAL_INT(0, store.take(store.ctx, 0u, 3, -4, &got));
}

static void test_mem_store_should_refuse_a_tile_when_full(void)
{
    rsm_tilestore_mem_t m;
    rsm_tile_store_t s;
    rsm_tile_t t = tile_at(0u, 0, 0, 1u);
    int32_t k;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tilestore_mem_init(&m, tiles, 5u, index_, 4u, &s));
    for (k = 0; k < 5; ++k) {
        t.tx = (int16_t)k;
        TEST_ASSERT_EQUAL_INT(RSM_OK, s.put(s.ctx, &t));
    }
    t.tx = 5;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM, s.put(s.ctx, &t));
    TEST_ASSERT_EQUAL_UINT32(5u, s.count(s.ctx));
}

/* Thousands of puts and takes against a model (a flag per place): every
 * answer as the model says, and the tile given back the one put. */
static void test_mem_store_should_match_a_model_through_many_puts_and_takes(void)
{
    static uint8_t held[4][32][32];
    uint32_t rng = 12345u;
    uint32_t n = 0;
    uint32_t k;
    memset(held, 0, sizeof held);
    for (k = 0; k < 40000u; ++k) {
        uint32_t level;
        int32_t tx;
        int32_t ty;
        rsm_tile_t t;
        rsm_tile_t got;
        rng = rng * 1664525u + 1013904223u;
        level = (rng >> 8) & 3u;
        tx = (int32_t)((rng >> 12) & 31u) - 16;
        ty = (int32_t)((rng >> 20) & 31u) - 16;
        t = tile_at(level, tx, ty, (uint8_t)(tx * 7 + ty * 3 + (int32_t)level));
        if ((rng >> 30) & 1u) {
            const int rc = store.put(store.ctx, &t);
            TEST_ASSERT_EQUAL_INT(held[level][tx + 16][ty + 16] ? RSM_ERR_FORMAT : RSM_OK, rc);
            n += held[level][tx + 16][ty + 16] ? 0u : 1u;
            held[level][tx + 16][ty + 16] = 1u;
        } else {
            const int r = store.take(store.ctx, level, tx, ty, &got);
            TEST_ASSERT_EQUAL_INT(held[level][tx + 16][ty + 16], r);
            if (r == 1) {
                TEST_ASSERT_EQUAL_MEMORY(&t, &got, sizeof got);
                --n;
            }
            held[level][tx + 16][ty + 16] = 0u;
        }
        TEST_ASSERT_EQUAL_UINT32(n, store.count(store.ctx));
    }
    TEST_ASSERT_TRUE(n > 100u);
}

/* Writes value v into cell (gx, gy) of level 0 as a newer write than
 * anything before it. */
static void raise_newer(rsm_tmap_t *m, int32_t gx, int32_t gy, uint32_t v)
{
    rsm_tmap_cursor_t c;
    rsm_tmap_cursor_init(&c, 0u);
    m->stamp++;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_raise(m, &c, gx, gy, v));
}

/* The cell at the middle of tile k of a row far from the origin. */
static int32_t cell_x(uint32_t k)
{
    return (int32_t)(k * (uint32_t)RSM_TMAP_TILE_SIDE) + 3;
}

/* A pool filled twice over: without a store the first places are
 * forgotten; with one, they are kept, each in the pool or the store (never
 * both), and come back with their cells when a scan's points fall in them. */
/* The sum of the places of level 0's tiles in the pool (and the store). */
static uint32_t places_sig(const rsm_tmap_t *m, int with_store)
{
    uint32_t sig = 0;
    uint32_t k;
    for (k = 0; k < m->used; ++k) {
        if ((m->tile[k].stamp >> 30) == 0u) {
            sig += rsm_tmap_place_sig(0u, m->tile[k].tx, m->tile[k].ty);
        }
    }
    for (k = 0; with_store && k < store.count(store.ctx); ++k) {
        rsm_tile_t t;
        TEST_ASSERT_EQUAL_INT(RSM_OK, store.at(store.ctx, k, &t));
        sig += (t.stamp >> 30) == 0u ? rsm_tmap_place_sig(0u, t.tx, t.ty) : 0u;
    }
    return sig;
}

static void test_map_should_keep_what_its_pool_lets_go_in_the_store(void)
{
    const uint32_t n = (uint32_t)RSM_TMAP_TILES + 40u;
    const rsm_tmap_config_t tc = rsm_tmap_config_default();
    const rsm_pose_t at = {0.0f, 0.0f, 0.0f};
    rsm_point_t pts[8];
    uint32_t k;
    int with;
    for (with = 0; with < 2; ++with) {
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_init(&map, &tc));
        map.store = with ? &store : NULL;
        store.clear(store.ctx);
        for (k = 0; k < n; ++k) {
            raise_newer(&map, cell_x(k), 5, 9u + (k & 3u));
        }
        TEST_ASSERT_EQUAL_UINT32(RSM_TMAP_TILES, map.used);
        TEST_ASSERT_EQUAL_UINT32(40u, map.counters.evicted);
        TEST_ASSERT_EQUAL_UINT32(with ? 40u : 0u, map.counters.stored);
        TEST_ASSERT_EQUAL_UINT32(with ? 40u : 0u, store.count(store.ctx));
        /* The tiles writes began less those that ended: with a store, every
         * one (kept there), else the pool's (rsm_tmap_t.churn, what a global
         * search's grids count on). */
        TEST_ASSERT_EQUAL_UINT32(with ? n : (uint32_t)RSM_TMAP_TILES, map.churn[0]);
        TEST_ASSERT_EQUAL_UINT32(places_sig(&map, with), map.churn_sig[0]);
        /* The oldest went, the newest stayed. */
        TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&map, 0u, cell_x(0), 5));
        TEST_ASSERT_EQUAL_UINT8(9u + ((n - 1u) & 3u), rsm_tmap_value(&map, 0u, cell_x(n - 1u), 5));
        /* A scan whose points fall in the first eight tiles. */
        for (k = 0; k < 8u; ++k) {
            pts[k].x = ((float)cell_x(k) + 0.5f) * tc.cell_m;
            pts[k].y = 5.5f * tc.cell_m;
        }
        TEST_ASSERT_EQUAL_UINT32(with ? 8u : 0u, rsm_tmap_fetch(&map, &at, pts, 8u, 0.0f));
        for (k = 0; k < 8u; ++k) {
            TEST_ASSERT_EQUAL_UINT8(with ? 9u + (k & 3u) : 0u, rsm_tmap_value(&map, 0u, cell_x(k), 5));
        }
        TEST_ASSERT_EQUAL_UINT32(with ? 8u : 0u, map.counters.fetched);
        /* Tiles back from the store are none begun. */
        TEST_ASSERT_EQUAL_UINT32(with ? n : (uint32_t)RSM_TMAP_TILES, map.churn[0]);
        TEST_ASSERT_EQUAL_UINT32(places_sig(&map, with), map.churn_sig[0]);
        if (with) {
            /* Eight others made room, into the store; each place once. */
            TEST_ASSERT_EQUAL_UINT32(48u, map.counters.stored);
            TEST_ASSERT_EQUAL_UINT32(40u, store.count(store.ctx));
            for (k = 0; k < store.count(store.ctx); ++k) {
                rsm_tile_t t;
                TEST_ASSERT_EQUAL_INT(RSM_OK, store.at(store.ctx, k, &t));
                TEST_ASSERT_EQUAL_UINT32(RSM_TMAP_NONE, rsm_tmap_find_slot(&map, t.stamp >> 30, t.tx, t.ty));
            }
            for (k = 0; k < n; ++k) {
                const int32_t tx = cell_x(k) >> RSM_TMAP_TILE_LOG2;
                rsm_tile_t t;
                const int in_pool = rsm_tmap_find_slot(&map, 0u, tx, 0) != RSM_TMAP_NONE;
                const int in_store = store.take(store.ctx, 0u, tx, 0, &t);
                TEST_ASSERT_TRUE(in_pool != in_store);
                if (in_store) {
                    TEST_ASSERT_EQUAL_INT(RSM_OK, store.put(store.ctx, &t));
                }
            }
        }
    }
}

/* The coarse levels a search reads come back whole (rsm_tmap_take_back):
 * into a full pool, the tiles the store holds under a coarsest tile in the
 * pool, with their cells; a tile of a finer level than asked stays there;
 * the pool's oldest go into the store in their place; a second call finds
 * nothing to take; a pool with no slot but the coarse levels' says so. */
static void test_map_should_take_back_the_coarse_levels(void)
{
    const rsm_tmap_config_t tc = rsm_tmap_config_default();
    const uint32_t top = (uint32_t)tc.levels - 1u;
    uint32_t looked = 0;
    uint32_t before;
    uint32_t k;
    int full = -1;
    rsm_tile_t t;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_init(&map, &tc));
    map.store = &store;
    /* Two coarsest tiles in the pool; the four under the first, and one
     * under the second, in the store, with a tile of the finest level. */
    t = tile_at(top, 3, 5, 0xFF);
    t.stamp = (top << 30) | (1u << 29); /* saturated: kept like the building's outline */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_restore(&map, &t));
    t.tx = 4;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_restore(&map, &t));
    for (k = 0; k < 4u; ++k) {
        t = tile_at(top - 1u, 6 + (int32_t)(k & 1u), 10 + (int32_t)(k >> 1), 0x55);
        TEST_ASSERT_EQUAL_INT(RSM_OK, store.put(store.ctx, &t));
    }
    t = tile_at(top - 1u, 9, 11, 0x33);
    TEST_ASSERT_EQUAL_INT(RSM_OK, store.put(store.ctx, &t));
    t = tile_at(0u, 90, 90, 0x77);
    TEST_ASSERT_EQUAL_INT(RSM_OK, store.put(store.ctx, &t));
    for (k = 0; map.used < (uint32_t)RSM_TMAP_TILES; ++k) {
        raise_newer(&map, cell_x(k), 5, 9u);
    }
    before = store.count(store.ctx);
    TEST_ASSERT_EQUAL_UINT32(6u, before);
    /* Three at most, then the rest. */
    TEST_ASSERT_EQUAL_UINT32(3u, rsm_tmap_take_back(&map, top - 1u, 3u, &looked, NULL));
    TEST_ASSERT_EQUAL_UINT32(2u, rsm_tmap_take_back(&map, top - 1u, 3u, &looked, NULL));
    /* Four places under each coarsest tile, a sixteenth of the pool. */
    TEST_ASSERT_TRUE(looked >= 8u + (uint32_t)RSM_TMAP_TILES / 16u);
    for (k = 0; k < 4u; ++k) {
        const int32_t tx = 6 + (int32_t)(k & 1u);
        const int32_t ty = 10 + (int32_t)(k >> 1);
        TEST_ASSERT_TRUE(rsm_tmap_find_slot(&map, top - 1u, tx, ty) != RSM_TMAP_NONE);
        TEST_ASSERT_EQUAL_UINT8(5u, rsm_tmap_value(&map, top - 1u, tx * RSM_TMAP_TILE_SIDE, ty * RSM_TMAP_TILE_SIDE));
    }
    TEST_ASSERT_EQUAL_UINT8(3u, rsm_tmap_value(&map, top - 1u, 9 * RSM_TMAP_TILE_SIDE, 11 * RSM_TMAP_TILE_SIDE));
    TEST_ASSERT_EQUAL_UINT32(RSM_TMAP_NONE, rsm_tmap_find_slot(&map, 0u, 90, 90));
    /* As many of the pool's oldest went into the store: nothing lost. */
    TEST_ASSERT_EQUAL_UINT32(RSM_TMAP_TILES, map.used);
    TEST_ASSERT_EQUAL_UINT32(before, store.count(store.ctx));
    TEST_ASSERT_EQUAL_UINT32(0u, map.counters.unstored);
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_tmap_take_back(&map, top - 1u, 100u, &looked, &full));
    TEST_ASSERT_EQUAL_INT(0, full);
    /* A pool of coarsest tiles alone, a stored tile under one of them: no
     * slot for it (said), and it stays in the store. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_init(&map, &tc));
    map.store = &store;
    store.clear(store.ctx);
    for (k = 0; map.used < (uint32_t)RSM_TMAP_TILES; ++k) {
        t = tile_at(top, (int32_t)k, 0, 0xFF);
        t.stamp = (top << 30) | (1u << 29);
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_restore(&map, &t));
    }
    t = tile_at(top - 1u, 0, 0, 0x55);
    TEST_ASSERT_EQUAL_INT(RSM_OK, store.put(store.ctx, &t));
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_tmap_take_back(&map, top - 1u, 100u, &looked, &full));
    TEST_ASSERT_EQUAL_INT(1, full);
    TEST_ASSERT_EQUAL_UINT32(1u, store.count(store.ctx));
    TEST_ASSERT_EQUAL_UINT32(RSM_TMAP_NONE, rsm_tmap_find_slot(&map, top - 1u, 0, 0));
    /* No store: nothing to do. */
    map.store = NULL;
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_tmap_take_back(&map, 0u, 100u, &looked, &full));
    TEST_ASSERT_EQUAL_INT(0, full);
}

/* A return written into a place the store holds starts from the stored
 * tile, not from an empty one. */
static void test_map_write_should_start_from_the_stored_tile(void)
{
    const rsm_tmap_config_t tc = rsm_tmap_config_default();
    const uint32_t n = (uint32_t)RSM_TMAP_TILES + 1u;
    uint32_t k;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_init(&map, &tc));
    map.store = &store;
    for (k = 0; k < n; ++k) {
        raise_newer(&map, cell_x(k), 5, 6u);
    }
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&map, 0u, cell_x(0), 5));
    /* Another cell of the first tile. */
    raise_newer(&map, cell_x(0) + 1, 5, 2u);
    TEST_ASSERT_EQUAL_UINT8(6u, rsm_tmap_value(&map, 0u, cell_x(0), 5));
    TEST_ASSERT_EQUAL_UINT8(2u, rsm_tmap_value(&map, 0u, cell_x(0) + 1, 5));
    TEST_ASSERT_EQUAL_UINT32(1u, map.counters.fetched);
}

/* Maps the synthetic room along a short tour (exact odometry). */
static size_t map_room(rsm_localizer_t *l)
{
    static const rsm_synth_leg_t legs[] = {{1.0f, 0.0f}, {0.0f, 1.2f}, {0.6f, 0.0f}};
    const rsm_pose_t start = {-1.2f, -0.8f, 0.0f};
    const rsm_synth_world_t world = rsm_synth_world_room();
    const rsm_synth_scan_config_t sc = rsm_synth_scan_config_default();
    const size_t len = rsm_synth_path(&start, legs, sizeof legs / sizeof legs[0], 0.05f, 0.05f, path, PATH_CAP);
    size_t k;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(l, &cfg, &path[0], NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_set_store(l, &store));
    for (k = 0; k < len; ++k) {
        if (k > 0u) {
            const rsm_motion_t u = rsm_synth_motion(&path[k - 1u], &path[k], NULL);
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_motion(l, &u));
        }
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_synth_scan(&world, &path[k], &sc, NULL, (uint64_t)k * STEP_US, &scan));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(l, &scan, NULL));
    }
    while (rsm_tmap_write_run(&l->state.persistent.map, l->frame.world, 0u) != 0) {
    }
    return len;
}

/* Fills the rest of a localizer's pool, and more, with newer places far
 * away: the room goes into the store (with one). */
static void flood(rsm_localizer_t *l)
{
    uint32_t k;
    for (k = 0; k < (uint32_t)RSM_TMAP_TILES; ++k) {
        raise_newer(&l->state.persistent.map, 4000 + cell_x(k), 4000, 12u);
    }
}

/* The robot comes back to a room its pool let go: with the store the room
 * comes back before the match, which finds the robot where it is and the
 * room's walls as mapped; without, the room is forgotten. */
static void test_localizer_should_take_the_room_back_from_the_store(void)
{
    const rsm_synth_world_t world = rsm_synth_world_room();
    const rsm_synth_scan_config_t sc = rsm_synth_scan_config_default();
    rsm_localizer_report_t rep;
    size_t len;
    rsm_pose_t p;
    rsm_pose_t pose;
    int32_t gx;
    int32_t gy;
    uint8_t mapped;
    rsm_tmap_t *m;
    int with;
    for (with = 0; with < 2; ++with) {
        store.clear(store.ctx);
        len = map_room(&loc);
        m = &loc.state.persistent.map;
        if (!with) {
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_set_store(&loc, NULL));
        }
        /* The wall cell straight ahead of the last pose. */
        p = path[len - 1u];
        pose = rsm_localizer_pose(&loc);
        {
            /* The beam's end may fall on a cell's edge: the wall's cell is
             * the fullest beside it. */
            const float r = rsm_synth_cast(&world, p.x, p.y, p.theta, 20.0f);
            const int32_t cx = (int32_t)floorf((p.x + r * cosf(p.theta)) / m->cfg.cell_m);
            const int32_t cy = (int32_t)floorf((p.y + r * sinf(p.theta)) / m->cfg.cell_m);
            int32_t dx;
            int32_t dy;
            mapped = 0u;
            gx = cx;
            gy = cy;
            for (dy = -1; dy <= 1; ++dy) {
                for (dx = -1; dx <= 1; ++dx) {
                    const uint8_t v = rsm_tmap_value(m, 0u, cx + dx, cy + dy);
                    if (v > mapped) {
                        mapped = v;
                        gx = cx + dx;
                        gy = cy + dy;
                    }
                }
            }
        }
        TEST_ASSERT_TRUE(mapped >= m->cfg.saturation);
        flood(&loc);
        TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(m, 0u, gx, gy));
        TEST_ASSERT_EQUAL_UINT32(with ? m->counters.evicted : 0u, m->counters.stored);
        /* The same place again, a second later. */
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_synth_scan(&world, &p, &sc, NULL, (uint64_t)(len + 10u) * STEP_US, &scan));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(&loc, &scan, &rep));
        if (with) {
            TEST_ASSERT_TRUE(m->counters.fetched > 10u);
            TEST_ASSERT_EQUAL_UINT8(mapped, rsm_tmap_value(m, 0u, gx, gy));
            TEST_ASSERT_EQUAL_INT(RSM_SCAN_ACCEPTED, rep.outcome);
            TEST_ASSERT_TRUE(rsm_synth_pos_error(&rep.pose, &pose) < 0.01f);
        } else {
            TEST_ASSERT_EQUAL_UINT32(0u, m->counters.fetched);
            TEST_ASSERT_TRUE(rsm_tmap_value(m, 0u, gx, gy) < mapped);
        }
    }
}

/* A global search looks the store up for the levels it reads only when
 * the pool let tiles go since they last came back: a search with none let
 * go since the last costs the look-up less than the same search with one
 * counted gone, and finds the same; once the room went into the store,
 * the next search looks it up again. */
static void test_global_search_should_look_the_store_up_only_after_tiles_went(void)
{
    const rsm_synth_world_t world = rsm_synth_world_room();
    const rsm_synth_scan_config_t sc = rsm_synth_scan_config_default();
    const rsm_global_t *g = &loc.state.persistent.global;
    const rsm_tmap_t *m = &loc.state.persistent.map;
    rsm_localizer_report_t rep;
    rsm_localizer_report_t rep_other;
    uint32_t stored;
    size_t len;
    store.clear(store.ctx);
    cfg.global_budget = 0u; /* each search whole in the scan after the request */
    len = map_room(&loc);
    TEST_ASSERT_EQUAL_UINT32(0u, m->counters.stored); /* the pool holds the room */
    TEST_ASSERT_EQUAL_INT(RSM_OK,
                          rsm_synth_scan(&world, &path[len - 1u], &sc, NULL, (uint64_t)(len + 10u) * STEP_US, &scan));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_global(&loc));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(&loc, &scan, &rep));
    TEST_ASSERT_EQUAL_UINT32(1u, g->taken_back);
    TEST_ASSERT_EQUAL_UINT32(m->counters.stored, g->back_stored);
    /* Another store (here the same again): looked up anew. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_set_store(&loc, &store));
    TEST_ASSERT_EQUAL_UINT32(0u, g->taken_back);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_global(&loc));
    scan.stamp_us += STEP_US;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(&loc, &scan, &rep));
    TEST_ASSERT_EQUAL_UINT32(1u, g->taken_back);
    /* An import begun empties the map: what was built and taken back for
     * it stands no more. */
    TEST_ASSERT_EQUAL_UINT32(1u, g->cached);
    other = loc;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_import_begin(&other, NULL));
    TEST_ASSERT_EQUAL_UINT32(0u, other.state.persistent.global.taken_back);
    TEST_ASSERT_EQUAL_UINT32(0u, other.state.persistent.global.cached);
    /* Again, nothing let go since; beside it a copy that counts a tile
     * gone. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_global(&loc));
    other = loc;
    other.state.persistent.global.back_stored++;
    scan.stamp_us += STEP_US;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(&loc, &scan, &rep));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(&other, &scan, &rep_other));
    TEST_ASSERT_TRUE(rep.search_work > 0u);
    TEST_ASSERT_TRUE(rep_other.search_work > rep.search_work);
    TEST_ASSERT_EQUAL_INT(rep_other.outcome, rep.outcome);
    TEST_ASSERT_EQUAL_MEMORY(&rep_other.pose, &rep.pose, sizeof rep.pose);
    /* The room let go into the store: the next search looks it up again
     * (counted when the levels came back: tiles taken back take slots,
     * and newer places go into the store in turn). */
    flood(&loc);
    stored = m->counters.stored;
    TEST_ASSERT_TRUE(stored > g->back_stored);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_global(&loc));
    scan.stamp_us += STEP_US;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(&loc, &scan, &rep));
    TEST_ASSERT_TRUE(g->back_stored >= stored);
}

/* A pool with no slot for what the store holds of the levels a search
 * reads (every other tile of the coarsest level, kept whole with a store,
 * and the one tile of the level searched written by the update in
 * progress): the search goes on with what the pool holds, the stored tile
 * stays in the store, and the levels do not count as back whole, so the
 * next search looks the store up again. */
static void test_global_search_should_go_on_when_the_pool_has_no_slot(void)
{
    const rsm_pose_t at = {0.5f, 0.5f, 0.0f};
    const rsm_synth_world_t world = rsm_synth_world_room();
    const rsm_synth_scan_config_t sc = rsm_synth_scan_config_default();
    const rsm_global_t *g = &loc.state.persistent.global;
    rsm_tmap_t *m = &loc.state.persistent.map;
    rsm_localizer_report_t rep;
    uint32_t top;
    uint32_t k;
    rsm_tile_t t;
    store.clear(store.ctx);
    cfg.global_budget = 0u; /* each search whole in its scan */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &cfg, &at, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_set_store(&loc, &store));
    top = (uint32_t)m->cfg.levels - 1u;
    t = tile_at(top - 1u, 0, 0, 0x55);
    t.stamp = ((top - 1u) << 30) | m->stamp; /* age 0: not the pool's to let go */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_restore(m, &t));
    for (k = 0; m->used < (uint32_t)RSM_TMAP_TILES; ++k) {
        t = tile_at(top, (int32_t)k, 0, 0xFF);
        t.stamp = (top << 30) | m->stamp;
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_restore(m, &t));
    }
    /* Under the first coarsest tile, beside the one the pool holds. */
    t = tile_at(top - 1u, 1, 0, 0x55);
    TEST_ASSERT_EQUAL_INT(RSM_OK, store.put(store.ctx, &t));
    TEST_ASSERT_EQUAL_INT(RSM_OK,
                          rsm_synth_scan(&world, &at, &sc, NULL, (uint64_t)10u * STEP_US, &scan));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_global(&loc));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(&loc, &scan, &rep));
    /* It searched (no scan spent waiting for a slot) and nothing moved. */
    TEST_ASSERT_EQUAL_UINT32(1u, loc.counters.global_searches);
    TEST_ASSERT_TRUE(rep.search_work > 0u);
    TEST_ASSERT_EQUAL_UINT32(0u, g->taken_back);
    TEST_ASSERT_EQUAL_UINT32(1u, store.count(store.ctx));
    TEST_ASSERT_EQUAL_UINT32(RSM_TMAP_NONE, rsm_tmap_find_slot(m, top - 1u, 1, 0));
    TEST_ASSERT_EQUAL_UINT32((uint32_t)RSM_TMAP_TILES, m->used);
    /* The next search looks the store up again, and goes on again. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_global(&loc));
    scan.stamp_us += STEP_US;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(&loc, &scan, &rep));
    TEST_ASSERT_EQUAL_UINT32(2u, loc.counters.global_searches);
    TEST_ASSERT_EQUAL_UINT32(0u, g->taken_back);
    TEST_ASSERT_EQUAL_UINT32(1u, store.count(store.ctx));
}

/* A map with tiles in the store saves whole and loads back into a pool
 * and a store: the same tiles; without a store, or with one too small,
 * it is refused and the localizer keeps its map. */
static void test_saved_map_should_hold_the_pool_and_the_store(void)
{
    rsm_mapfile_info_t info;
    rsm_mapfile_info_t got;
    uint32_t pool_then;
    uint32_t k;
    rsm_tilestore_mem_t small;
    rsm_tile_store_t small_store;
    store.clear(store.ctx);
    (void)map_room(&loc);
    flood(&loc);
    TEST_ASSERT_TRUE(store.count(store.ctx) > 20u);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_save_map(&loc, ram_write, NULL, &info));
    TEST_ASSERT_EQUAL_UINT32(loc.state.persistent.map.used + store.count(store.ctx), info.tiles);
    TEST_ASSERT_EQUAL_UINT32(rsm_localizer_map_bytes(&loc), info.bytes);
    TEST_ASSERT_EQUAL_UINT32(saved_len, info.bytes);

    /* Without a store: more tiles than the pool holds. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&other, &cfg, &path[0], NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT, rsm_localizer_load_map(&other, ram_read, NULL, &got));
    TEST_ASSERT_EQUAL_UINT32(0u, other.state.persistent.map.used);
    /* With one too small. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tilestore_mem_init(&small, tiles2, 4u, index2, 4u, &small_store));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_set_store(&other, &small_store));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT, rsm_localizer_load_map(&other, ram_read, NULL, &got));
    TEST_ASSERT_EQUAL_UINT32(0u, small_store.count(small_store.ctx));

    /* With room: the pool full, the rest in the store, every tile as saved,
     * in one of them; the coarsest level whole in the pool. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tilestore_mem_init(&mem2, tiles2, STORE_TILES, index2, INDEX_LOG2, &store2));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_set_store(&other, &store2));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_load_map(&other, ram_read, NULL, &got));
    TEST_ASSERT_EQUAL_UINT32(info.tiles, got.tiles);
    pool_then = other.state.persistent.map.used;
    TEST_ASSERT_EQUAL_UINT32(RSM_TMAP_TILES, pool_then);
    TEST_ASSERT_EQUAL_UINT32(info.tiles - pool_then, store2.count(store2.ctx));
    {
        const rsm_tmap_t *a = &loc.state.persistent.map;
        const rsm_tmap_t *b = &other.state.persistent.map;
        const uint32_t top = (uint32_t)a->cfg.levels - 1u;
        uint32_t coarsest = 0;
        for (k = 0; k < info.tiles; ++k) {
            rsm_tile_t t;
            rsm_tile_t u;
            uint32_t s;
            if (k < a->used) {
                t = a->tile[k];
            } else {
                TEST_ASSERT_EQUAL_INT(RSM_OK, store.at(store.ctx, k - a->used, &t));
            }
            coarsest += (t.stamp >> 30) == top ? 1u : 0u;
            s = rsm_tmap_find_slot(b, t.stamp >> 30, t.tx, t.ty);
            if (s != RSM_TMAP_NONE) {
                TEST_ASSERT_EQUAL_MEMORY(&t, &b->tile[s], sizeof t);
                TEST_ASSERT_EQUAL_INT(0, store2.take(store2.ctx, t.stamp >> 30, t.tx, t.ty, &u));
            } else {
                TEST_ASSERT_EQUAL_INT(1, store2.take(store2.ctx, t.stamp >> 30, t.tx, t.ty, &u));
                TEST_ASSERT_EQUAL_MEMORY(&t, &u, sizeof t);
                TEST_ASSERT_EQUAL_INT(RSM_OK, store2.put(store2.ctx, &u));
            }
        }
        TEST_ASSERT_TRUE(coarsest > 0u);
        TEST_ASSERT_EQUAL_UINT32(coarsest < (uint32_t)RSM_TMAP_TILES ? coarsest : RSM_TMAP_TILES,
                                 rsm_tmap_tiles(b, top));
    }
    /* Saved again at once: the same tiles (a load only moves them). */
    {
        static uint8_t first[sizeof saved];
        const uint32_t first_len = saved_len;
        memcpy(first, saved, saved_len);
        saved_len = 0u;
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_set_pose(&other, &info.pose, NULL));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_save_map(&other, ram_write, NULL, NULL));
        TEST_ASSERT_EQUAL_UINT32(first_len, saved_len);
        TEST_ASSERT_EQUAL_MEMORY(first, saved, RSM_MAPFILE_HEADER_BYTES);
    }
    /* Loading again empties the store first: the same count, no place twice. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_load_map(&other, ram_read, NULL, &got));
    TEST_ASSERT_EQUAL_UINT32(info.tiles - pool_then, store2.count(store2.ctx));
}

/* A saved map whose tiles reach into the store, damaged: a bit flipped in
 * its header, in a tile the pool takes, in one the store takes, or in its
 * CRC, or the map cut short, is refused, and the localizer and its store
 * stay as they were (a store already holding another map's tiles). */
static void test_damaged_map_with_store_tiles_should_be_refused_whole(void)
{
    static rsm_localizer_t was;
    static uint8_t good[sizeof saved];
    rsm_mapfile_info_t info;
    uint32_t good_len;
    uint32_t bits[3][2];
    uint32_t r;
    uint32_t k;
    uint32_t refused = 0;
    store.clear(store.ctx);
    (void)map_room(&loc);
    flood(&loc);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_save_map(&loc, ram_write, NULL, &info));
    TEST_ASSERT_TRUE(info.tiles > (uint32_t)RSM_TMAP_TILES + 2u);
    memcpy(good, saved, saved_len);
    good_len = saved_len;
    /* The loading localizer holds a map of its own, part in its store. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tilestore_mem_init(&mem2, tiles2, STORE_TILES, index2, INDEX_LOG2, &store2));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&other, &cfg, &path[0], NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_set_store(&other, &store2));
    for (k = 0; k < (uint32_t)RSM_TMAP_TILES + 5u; ++k) {
        raise_newer(&other.state.persistent.map, cell_x(k), -77, 9u);
    }
    TEST_ASSERT_EQUAL_UINT32(5u, store2.count(store2.ctx));
    was = other;
    memcpy(tiles, tiles2, 5u * sizeof tiles[0]); /* the store's tiles as they were */
    /* Bit ranges: the header, the first tile past the pool's (the
     * store's first), the CRC (test_mapfile.c flips every bit of a map the
     * pool holds whole). */
    bits[0][0] = 0u;
    bits[0][1] = RSM_MAPFILE_HEADER_BYTES * 8u;
    bits[1][0] = (RSM_MAPFILE_HEADER_BYTES + (uint32_t)RSM_TMAP_TILES * RSM_MAPFILE_TILE_BYTES) * 8u;
    bits[1][1] = bits[1][0] + RSM_MAPFILE_TILE_BYTES * 8u;
    bits[2][0] = (good_len - 4u) * 8u;
    bits[2][1] = good_len * 8u;
    for (r = 0; r < 3u; ++r) {
        uint32_t b;
        for (b = bits[r][0]; b < bits[r][1]; ++b) {
            memcpy(saved, good, good_len);
            saved_len = good_len;
            saved[b / 8u] = (uint8_t)(saved[b / 8u] ^ (1u << (b % 8u)));
            TEST_ASSERT_TRUE(rsm_localizer_load_map(&other, ram_read, NULL, NULL) != RSM_OK);
            refused++;
        }
    }
    for (k = 0; k < 64u; ++k) {
        memcpy(saved, good, good_len);
        saved_len = (uint32_t)((uint64_t)good_len * k / 64u);
        TEST_ASSERT_TRUE(rsm_localizer_load_map(&other, ram_read, NULL, NULL) != RSM_OK);
        refused++;
    }
    TEST_ASSERT_EQUAL_UINT32((RSM_MAPFILE_HEADER_BYTES + RSM_MAPFILE_TILE_BYTES + 4u) * 8u + 64u, refused);
    TEST_ASSERT_EQUAL_MEMORY(&was.state.persistent.map, &other.state.persistent.map, sizeof was.state.persistent.map);
    TEST_ASSERT_EQUAL_UINT32(5u, store2.count(store2.ctx));
    TEST_ASSERT_EQUAL_MEMORY(tiles, tiles2, 5u * sizeof tiles[0]);
    /* And the map undamaged is taken. */
    memcpy(saved, good, good_len);
    saved_len = good_len;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_load_map(&other, ram_read, NULL, NULL));
    TEST_ASSERT_EQUAL_UINT32(info.tiles - (uint32_t)RSM_TMAP_TILES, store2.count(store2.ctx));
}

/* Flash for the store over a saved map: index words, erased to all ones,
 * each programmed once at most. */
static uint32_t flash_index[1u << INDEX_LOG2];
static uint32_t programmed_twice;
static uint8_t out_bits[(STORE_TILES + 3u * (uint32_t)RSM_TMAP_TILES + 64u + 7u) / 8u];

static int program_word(void *ctx, uint32_t at, uint32_t value)
{
    (void)ctx;
    if (flash_index[at] != 0xFFFFFFFFu) {
        programmed_twice++;
    }
    flash_index[at] &= value; /* NOR flash only clears bits */
    return 0;
}

/* A map larger than the pool, saved and put in "flash" with its index:
 * a localizer in localization mode loads it with the store over those
 * bytes, keeps only the bitmap in RAM, and takes a room the pool lacks
 * back from flash to match the robot there. */
static void test_rom_store_should_serve_a_saved_map_from_flash(void)
{
    const rsm_synth_world_t world = rsm_synth_world_room();
    const rsm_synth_scan_config_t sc = rsm_synth_scan_config_default();
    rsm_localizer_config_t frozen;
    rsm_tilestore_rom_t rom;
    rsm_tile_store_t rs;
    rsm_mapfile_info_t info;
    rsm_localizer_report_t rep;
    rsm_tile_t t;
    rsm_pose_t p;
    rsm_pose_t mapped_at;
    uint32_t ilog;
    size_t len;
    store.clear(store.ctx);
    len = map_room(&loc);
    mapped_at = rsm_localizer_pose(&loc);
    flood(&loc);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_save_map(&loc, ram_write, NULL, &info));
    ilog = rsm_tilestore_rom_index_log2(info.tiles);
    TEST_ASSERT_TRUE(ilog <= INDEX_LOG2);
    memset(flash_index, 0xFF, sizeof flash_index);
    programmed_twice = 0u;
    /* Not a map; an index too small. */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT,
                          rsm_tilestore_rom_build_index(saved, saved_len - 1u, flash_index, ilog, program_word, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL,
                          rsm_tilestore_rom_build_index(saved, saved_len, flash_index, ilog - 1u, program_word, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK,
                          rsm_tilestore_rom_build_index(saved, saved_len, flash_index, ilog, program_word, NULL));
    TEST_ASSERT_EQUAL_UINT32(0u, programmed_twice);
    /* Built once only: the region is no longer erased. */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_IO,
                          rsm_tilestore_rom_build_index(saved, saved_len, flash_index, ilog, program_word, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tilestore_rom_init(&rom, saved, saved_len, flash_index, ilog, out_bits,
                                                                (info.tiles + 7u) / 8u - 1u, &rs));
    /* A region longer than the map (flash pages) is taken as the map. */
    TEST_ASSERT_TRUE(saved_len + RSM_MAPFILE_TILE_BYTES <= sizeof saved);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tilestore_rom_init(&rom, saved, saved_len + RSM_MAPFILE_TILE_BYTES, flash_index,
                                                         ilog, out_bits, (uint32_t)sizeof out_bits, &rs));
    TEST_ASSERT_EQUAL_UINT32(info.tiles, rom.tiles);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tilestore_rom_init(&rom, saved, saved_len, flash_index, ilog, out_bits,
                                                         (uint32_t)sizeof out_bits, &rs));
    TEST_ASSERT_EQUAL_UINT32(0u, rs.count(rs.ctx));

    frozen = cfg;
    frozen.map_frozen = 1u;
    p = path[len - 1u];
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&other, &frozen, &p, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_set_store(&other, &rs));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_load_map(&other, ram_read, NULL, NULL));
    TEST_ASSERT_EQUAL_UINT32(info.tiles - (uint32_t)RSM_TMAP_TILES, rs.count(rs.ctx));
    /* The tiles held are the map's, each once: the pool's are out. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rs.at(rs.ctx, 0u, &t));
    TEST_ASSERT_EQUAL_UINT32(RSM_TMAP_NONE, rsm_tmap_find_slot(&other.state.persistent.map, t.stamp >> 30, t.tx, t.ty));
    /* Only a tile as the map has it comes back to flash. */
    {
        rsm_tile_t changed;
        TEST_ASSERT_EQUAL_INT(1, rs.take(rs.ctx, t.stamp >> 30, t.tx, t.ty, &changed));
        TEST_ASSERT_EQUAL_INT(0, rs.take(rs.ctx, t.stamp >> 30, t.tx, t.ty, &changed));
        changed.cell[0] = (uint8_t)(changed.cell[0] ^ 0x11u);
        TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM, rs.put(rs.ctx, &changed));
        changed.cell[0] = (uint8_t)(changed.cell[0] ^ 0x11u);
        changed.stamp = (changed.stamp & 0xC0000000u) | 1u; /* restamped, as the pool does */
        TEST_ASSERT_EQUAL_INT(RSM_OK, rs.put(rs.ctx, &changed));
        TEST_ASSERT_EQUAL_INT(RSM_ERR_FORMAT, rs.put(rs.ctx, &changed));
        changed.tx = (int16_t)(changed.tx + 1000);
        TEST_ASSERT_EQUAL_INT(RSM_ERR_NOMEM, rs.put(rs.ctx, &changed));
    }
    /* The robot in the room, which the pool does not hold: it comes back
     * from flash and the scan is matched where the mapper was. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_synth_scan(&world, &p, &sc, NULL, (uint64_t)(len + 10u) * STEP_US, &scan));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(&other, &scan, &rep));
    TEST_ASSERT_TRUE(other.state.persistent.map.counters.fetched > 10u);
    TEST_ASSERT_EQUAL_INT(RSM_SCAN_ACCEPTED, rep.outcome);
    /* Started from the truth, one scan moves it towards the map's frame
     * (the mapper's estimate, a centimetre or two off the truth). */
    TEST_ASSERT_TRUE(rep.fit_ratio > 0.6f);
    TEST_ASSERT_TRUE(rsm_synth_pos_error(&rep.pose, &p) < 0.03f);
    TEST_ASSERT_TRUE(rsm_synth_pos_error(&rep.pose, &mapped_at) < 0.06f);
}

static void test_set_store_should_refuse_what_it_cannot_use(void)
{
    rsm_tile_store_t broken = store;
    rsm_localizer_config_t icp = rsm_localizer_config_default();
    const rsm_pose_t zero = {0.0f, 0.0f, 0.0f};
    memset(&loc, 0, sizeof loc);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_set_store(&loc, &store));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &cfg, &zero, NULL));
    broken.take = NULL;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_localizer_set_store(&loc, &broken));
    TEST_ASSERT_NULL(loc.state.persistent.map.store);
    icp.method = RSM_METHOD_ODOMETRY;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&other, &icp, &zero, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_localizer_set_store(&other, &store));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_mem_store_should_refuse_bad_set_ups);
    RUN_TEST(test_mem_store_should_give_each_tile_back_once);
    RUN_TEST(test_mem_store_should_refuse_a_tile_when_full);
    RUN_TEST(test_mem_store_should_match_a_model_through_many_puts_and_takes);
    RUN_TEST(test_map_should_keep_what_its_pool_lets_go_in_the_store);
    RUN_TEST(test_map_write_should_start_from_the_stored_tile);
    RUN_TEST(test_map_should_take_back_the_coarse_levels);
    RUN_TEST(test_localizer_should_take_the_room_back_from_the_store);
    RUN_TEST(test_global_search_should_look_the_store_up_only_after_tiles_went);
    RUN_TEST(test_global_search_should_go_on_when_the_pool_has_no_slot);
    RUN_TEST(test_saved_map_should_hold_the_pool_and_the_store);
    RUN_TEST(test_damaged_map_with_store_tiles_should_be_refused_whole);
    RUN_TEST(test_rom_store_should_serve_a_saved_map_from_flash);
    RUN_TEST(test_set_store_should_refuse_what_it_cannot_use);
    return UNITY_END();
}
