/* The persistent tile map: configuration checks, hits and misses along a
 * beam, tiles taken only for returns, the index against a reference model
 * through allocation and eviction, what happens when the pool is full, and
 * the interpolated occupancy and its gradient. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "rsm/config.h"
#include "rsm/status.h"
#include "map/tilemap.h"
#include "map/tmap_read.h"
#include "synth.h"
#include "unity.h"

static rsm_tmap_t map;
static rsm_tmap_config_t cfg;

void setUp(void)
{
    memset(&map, 0xA5, sizeof map); /* init must not rely on zeroed storage */
    cfg = rsm_tmap_config_default();
    cfg.levels = 1u;
    cfg.cell_m = 0.1f; /* the coordinates below are written for 10 cm cells */
}

void tearDown(void)
{
}

static void init(void)
{
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_init(&map, &cfg));
}

/* Cell of a world coordinate on level 0. */
static int32_t cell(float v)
{
    return (int32_t)floorf(v / cfg.cell_m);
}

static void update_one(float ox, float oy, float px, float py)
{
    const rsm_point_t o = {ox, oy};
    const rsm_point_t p = {px, py};
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_update(&map, &o, &p, 1u));
}

void test_tmap_init_should_reject_bad_configs(void)
{
    rsm_tmap_config_t c;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tmap_init(NULL, &cfg));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tmap_init(&map, NULL));
#define BAD(field, value)                                                   \
    do {                                                                    \
        c = cfg;                                                            \
        c.field = value;                                                    \
        TEST_ASSERT_EQUAL_INT_MESSAGE(RSM_ERR_INVAL, rsm_tmap_init(&map, &c), #field); \
    } while (0)
    BAD(cell_m, 0.0f);
    BAD(cell_m, NAN);
    BAD(levels, 0u);
    BAD(levels, (uint8_t)(RSM_TMAP_LEVELS + 1));
    BAD(hit_inc, 0u);
    BAD(hit_inc, 16u);
    BAD(miss_dec, 16u);
    BAD(saturation, 0u);
    BAD(saturation, 16u);
#undef BAD
    c = rsm_tmap_config_default();
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_init(&map, &c));
    TEST_ASSERT_EQUAL_UINT32(0u, map.used);
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&map, 0u, 3, -7));
}

void test_tmap_update_should_add_hits_and_saturate(void)
{
    int i;
    init();
    update_one(0.05f, 0.05f, 1.03f, 0.05f);
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc, rsm_tmap_value(&map, 0u, cell(1.03f), cell(0.05f)));
    TEST_ASSERT_EQUAL_UINT32(1u, map.used);
    TEST_ASSERT_EQUAL_UINT32(1u, map.counters.allocated);
    for (i = 0; i < 10; ++i) {
        update_one(0.05f, 0.05f, 1.03f, 0.05f);
    }
    TEST_ASSERT_EQUAL_UINT8(RSM_TMAP_MAX_VALUE, rsm_tmap_value(&map, 0u, cell(1.03f), cell(0.05f)));
    TEST_ASSERT_EQUAL_UINT32(11u, map.counters.updates);
    TEST_ASSERT_EQUAL_FLOAT(1.0f, rsm_tmap_occupancy(&map, 0u, 1.03f, 0.05f));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rsm_tmap_occupancy(&map, 0u, 0.95f, 0.05f));
}

void test_tmap_update_should_clear_along_the_beam_but_not_near_the_return(void)
{
    int32_t gx;
    int i;
    /* A wall of returns along x = 2.05 from the origin: then move it to x = 3.05
     * so that beams pass through the old one (the wall rule is off by
     * default: see test_tmap_update_should_not_write_returns_behind_a_wall). */
    init();
    for (i = 0; i < 2; ++i) {
        update_one(0.05f, 0.05f, 2.05f, 0.05f);
    }
    TEST_ASSERT_EQUAL_UINT8(2u * cfg.hit_inc, rsm_tmap_value(&map, 0u, cell(2.05f), 0));
    for (i = 0; i < 3; ++i) {
        update_one(0.05f, 0.05f, 3.05f, 0.05f);
    }
    /* The old return lost one per beam through it; the new one gained. */
    TEST_ASSERT_EQUAL_UINT8(2u * cfg.hit_inc - 3u * cfg.miss_dec, rsm_tmap_value(&map, 0u, cell(2.05f), 0));
    TEST_ASSERT_EQUAL_UINT8(3u * cfg.hit_inc, rsm_tmap_value(&map, 0u, cell(3.05f), 0));
    /* clear_margin cells before the return keep their value: put a return
     * there first, then one just behind it. */
    init();
    update_one(0.05f, 0.05f, 1.95f, 0.05f);
    update_one(0.05f, 0.05f, 2.05f, 0.05f);
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc, rsm_tmap_value(&map, 0u, cell(1.95f), 0));
    update_one(0.05f, 0.05f, 2.25f, 0.05f);
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc - cfg.miss_dec, rsm_tmap_value(&map, 0u, cell(1.95f), 0));
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc - cfg.miss_dec, rsm_tmap_value(&map, 0u, cell(2.05f), 0));
    /* Values never go below 0, and cells along the way stay at 0. */
    for (gx = 1; gx < cell(1.95f); ++gx) {
        TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&map, 0u, gx, 0));
    }
}

/* The cells a beam from cell (x0, y0) to (x1, y1) lowers, in the plainest
 * form of Bresenham's walk (one step at a time over every octant), to
 * check the library's walk, which goes tile by tile, against. */
#define BEAM_SPAN 48
static void reference_beam(int32_t x0, int32_t y0, int32_t x1, int32_t y1, uint32_t margin,
                           uint8_t lowered[BEAM_SPAN][BEAM_SPAN])
{
    const int32_t dx = x1 > x0 ? x1 - x0 : x0 - x1;
    const int32_t dy = y1 > y0 ? y1 - y0 : y0 - y1;
    const int32_t sx = x1 > x0 ? 1 : -1;
    const int32_t sy = y1 > y0 ? 1 : -1;
    const int32_t steps = dx > dy ? dx : dy;
    int32_t err = dx - dy;
    int32_t k;
    for (k = 0; k < steps - (int32_t)margin; ++k) {
        const int32_t e2 = 2 * err;
        lowered[y0 + BEAM_SPAN / 2][x0 + BEAM_SPAN / 2]++;
        if (e2 > -dy) {
            err -= dy;
            x0 += sx;
        }
        if (e2 < dx) {
            err += dx;
            y0 += sy;
        }
    }
}

void test_tmap_update_should_lower_exactly_the_cells_of_bresenhams_line(void)
{
    /* A block of 48 x 48 cells (6 x 6 tiles, within the smallest pool the
     * tests build; half of them at negative coordinates) every one of
     * which holds 8; then beams in every
     * octant, from inside tiles and from their corners, along the axes
     * and the diagonals, each checked cell by cell. */
    static const int32_t from[][2] = {{0, 0}, {-1, -1}, {3, -5}, {-8, 7}, {7, 8}, {-20, 13}};
    static uint8_t lowered[BEAM_SPAN][BEAM_SPAN];
    const float a = 0.1f;
    int32_t gx;
    int32_t gy;
    size_t f;
    int32_t e;
    cfg.miss_dec = 0u; /* filling: no beam lowers anything */
    init();
    for (gy = -BEAM_SPAN / 2; gy < BEAM_SPAN / 2; ++gy) {
        for (gx = -BEAM_SPAN / 2; gx < BEAM_SPAN / 2; ++gx) {
            const float x = ((float)gx + 0.5f) * a;
            const float y = ((float)gy + 0.5f) * a;
            update_one(x, y, x, y);
            update_one(x, y, x, y);
        }
    }
    for (gy = -BEAM_SPAN / 2; gy < BEAM_SPAN / 2; ++gy) {
        for (gx = -BEAM_SPAN / 2; gx < BEAM_SPAN / 2; ++gx) {
            TEST_ASSERT_EQUAL_UINT8(2u * cfg.hit_inc, rsm_tmap_value(&map, 0u, gx, gy));
        }
    }
    map.cfg.miss_dec = 1u;
    for (f = 0; f < sizeof from / sizeof from[0]; ++f) {
        /* Ends all round the edge of the block, one cell in from it. */
        for (e = 0; e < 4 * (BEAM_SPAN - 2); e += 3) {
            const int32_t side = e / (BEAM_SPAN - 2);
            const int32_t along = e % (BEAM_SPAN - 2) - (BEAM_SPAN / 2 - 1);
            const int32_t lim = BEAM_SPAN / 2 - 1;
            const int32_t ex = side == 0 ? along : side == 1 ? lim - 1 : side == 2 ? -along : -lim;
            const int32_t ey = side == 0 ? -lim : side == 1 ? along : side == 2 ? lim - 1 : -along;
            const rsm_point_t o = {((float)from[f][0] + 0.5f) * a, ((float)from[f][1] + 0.5f) * a};
            const rsm_point_t p = {((float)ex + 0.5f) * a, ((float)ey + 0.5f) * a};
            static uint8_t before[BEAM_SPAN][BEAM_SPAN];
            for (gy = 0; gy < BEAM_SPAN; ++gy) {
                for (gx = 0; gx < BEAM_SPAN; ++gx) {
                    before[gy][gx] = rsm_tmap_value(&map, 0u, gx - BEAM_SPAN / 2, gy - BEAM_SPAN / 2);
                }
            }
            memset(lowered, 0, sizeof lowered);
            reference_beam(from[f][0], from[f][1], ex, ey, cfg.clear_margin, lowered);
            TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_update(&map, &o, &p, 1u));
            for (gy = 0; gy < BEAM_SPAN; ++gy) {
                for (gx = 0; gx < BEAM_SPAN; ++gx) {
                    const int hit = gx - BEAM_SPAN / 2 == ex && gy - BEAM_SPAN / 2 == ey;
                    int want = (int)before[gy][gx] - (int)lowered[gy][gx];
                    want = want < 0 ? 0 : want;
                    want = hit ? (want + (int)cfg.hit_inc > 15 ? 15 : want + (int)cfg.hit_inc) : want;
                    if ((int)rsm_tmap_value(&map, 0u, gx - BEAM_SPAN / 2, gy - BEAM_SPAN / 2) != want) {
                        char msg[96];
                        snprintf(msg, sizeof msg, "beam (%d, %d) -> (%d, %d), cell (%d, %d) got %d want %d", (int)from[f][0],
                                 (int)from[f][1], (int)ex, (int)ey, (int)(gx - BEAM_SPAN / 2),
                                 (int)(gy - BEAM_SPAN / 2), (int)rsm_tmap_value(&map, 0u, gx - BEAM_SPAN / 2, gy - BEAM_SPAN / 2), want);
                        TEST_FAIL_MESSAGE(msg);
                    }
                }
            }
        }
    }
}

void test_tmap_update_should_take_tiles_only_for_returns(void)
{
    init();
    /* A long beam through space that holds no tile takes only the tile of
     * its return. */
    update_one(-5.0f, -5.0f, 5.0f, 5.0f);
    TEST_ASSERT_EQUAL_UINT32(1u, map.used);
    TEST_ASSERT_EQUAL_UINT32(1u, rsm_tmap_tiles(&map, 0u));
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc, rsm_tmap_value(&map, 0u, cell(5.0f), cell(5.0f)));
}

void test_tmap_update_should_write_every_level(void)
{
    uint32_t level;
    cfg.levels = (uint8_t)RSM_TMAP_LEVELS;
    cfg.splat_from = (uint8_t)RSM_TMAP_LEVELS; /* whole increments everywhere */
    init();
    update_one(0.0f, 0.0f, 1.23f, -0.77f);
    for (level = 0; level < (uint32_t)RSM_TMAP_LEVELS; ++level) {
        const float a = rsm_tmap_cell(&map, level);
        TEST_ASSERT_EQUAL_FLOAT(cfg.cell_m * (float)(1u << level), a);
        TEST_ASSERT_EQUAL_UINT32(1u, rsm_tmap_tiles(&map, level));
        TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc, rsm_tmap_value(&map, level, (int32_t)floorf(1.23f / a),
                                                            (int32_t)floorf(-0.77f / a)));
    }
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&map, (uint32_t)RSM_TMAP_LEVELS, 0, 0));
}

void test_tmap_update_should_share_a_return_among_four_cells_on_coarse_levels(void)
{
    /* Level 1 has 0.2 m cells with centres at 0.1 + 0.2 k. */
    cfg.levels = 2u;
    cfg.splat_from = 1u;
    init();
    /* At a cell centre: all of it to that cell. */
    update_one(0.0f, 0.0f, 1.1f, 0.5f);
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc, rsm_tmap_value(&map, 1u, 5, 2));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&map, 1u, 6, 2));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&map, 1u, 5, 3));
    /* Half-way between two centres in x: half to each. */
    update_one(0.0f, 0.0f, 2.2f, -0.3f);
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc / 2u, rsm_tmap_value(&map, 1u, 10, -2));
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc / 2u, rsm_tmap_value(&map, 1u, 11, -2));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&map, 1u, 10, -1));
    /* The interpolated occupancy there is symmetric about the return. */
    {
        float dx;
        float dy;
        const float a = rsm_tmap_sample(&map, 1u, 2.15f, -0.3f, &dx, &dy);
        const float b = rsm_tmap_sample(&map, 1u, 2.25f, -0.3f, &dx, &dy);
        TEST_ASSERT_FLOAT_WITHIN(1e-5f, a, b);
    }
    /* The finest level still takes whole increments. */
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc, rsm_tmap_value(&map, 0u, cell(2.2f), cell(-0.3f)));
}

void test_tmap_update_should_skip_non_finite_points_and_refuse_bad_arguments(void)
{
    const rsm_point_t o = {0.0f, 0.0f};
    const rsm_point_t bad_o = {NAN, 0.0f};
    rsm_point_t p[3] = {{NAN, 1.0f}, {INFINITY, 0.0f}, {1.0f, 1.0f}};
    init();
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_update(&map, &o, p, 3u));
    TEST_ASSERT_EQUAL_UINT32(1u, map.used);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tmap_update(&map, &bad_o, p, 3u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tmap_update(&map, &o, NULL, 3u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tmap_update(NULL, &o, p, 3u));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_update(&map, &o, NULL, 0u));
    /* Beyond the tile coordinate range: counted, not written. */
    p[0].x = 5.0e5f;
    p[0].y = 0.0f;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_update(&map, &o, p, 1u));
    TEST_ASSERT_EQUAL_UINT32(1u, map.counters.outside);
    TEST_ASSERT_EQUAL_UINT32(1u, map.used);
}

/* Reference model of which tiles the map holds: key, last write, the value
 * of its one cell, and the slot it sits in (ties in age go to the lowest). */
typedef struct model_tile {
    int32_t tx;
    int32_t ty;
    uint32_t written;
    uint32_t value;
    uint32_t slot;
    int held;
} model_tile_t;

/* The model's reuse rule, as tilemap.h states it for one level: age, times
 * 2^unconfirmed_shift while the cell is below saturation. */
static uint32_t model_score(const model_tile_t *t, uint32_t step)
{
    const uint32_t age = step - t->written;
    return t->value >= cfg.saturation ? age : age << cfg.unconfirmed_shift;
}

/* More keys than the pool holds, so that slots are reused. */
#define MODEL_KEYS (RSM_TMAP_TILES + 100)

static model_tile_t model[MODEL_KEYS];

static void model_check(uint32_t step, float tile_m)
{
    size_t k;
    for (k = 0; k < (size_t)MODEL_KEYS; ++k) {
        const float x = ((float)model[k].tx + 0.5f) * tile_m;
        const float y = ((float)model[k].ty + 0.5f) * tile_m;
        if (model[k].held != (rsm_tmap_occupancy(&map, 0u, x, y) > 0.0f)) {
            char msg[80];
            snprintf(msg, sizeof msg, "step %u key %u: model says %s", (unsigned)step, (unsigned)k,
                     model[k].held ? "held" : "not held");
            TEST_FAIL_MESSAGE(msg);
        }
    }
}

/* Fills the pool one key per update, then writes batch random keys per
 * update (repeats allowed): each new one must take the slot of the least
 * recently written tile not written by the same update, where a tile
 * written once (below saturation) ages 2^unconfirmed_shift times faster.
 * A batch above RSM_TMAP_VICTIMS evicts more tiles in one write than one
 * search of the pool remembers. */
static uint32_t run_model(size_t batch, uint32_t updates)
{
    static rsm_point_t p[2u * RSM_TMAP_VICTIMS + 8u];
    rsm_synth_rng_t rng;
    uint32_t held = 0;
    uint32_t evictions = 0;
    uint32_t most = 0; /* evictions of one update at most */
    size_t next = 0;   /* keys in turn, as a robot reaches new ground */
    uint32_t step;
    const float tile_m = cfg.cell_m * (float)RSM_TMAP_TILE_SIDE;
    const rsm_point_t o = {0.0f, 0.0f};
    size_t k;
    TEST_ASSERT_TRUE(batch <= sizeof p / sizeof p[0]);
    cfg.miss_dec = 0u; /* only the index is under test */
    init();
    rsm_synth_rng_seed(&rng, 77u);
    for (k = 0; k < (size_t)MODEL_KEYS; ++k) {
        /* Keys over all four quadrants, rows 128 wide. */
        model[k].tx = (int32_t)(k % 128u) - 64;
        model[k].ty = (int32_t)(k / 128u) - 40;
        model[k].held = 0;
    }
    for (step = 1; step <= (uint32_t)RSM_TMAP_TILES + updates; ++step) {
        const size_t n = step <= (uint32_t)RSM_TMAP_TILES ? 1u : batch;
        const uint32_t before = map.counters.evicted;
        size_t b;
        for (b = 0; b < n; ++b) {
            /* With batches, every other key is the next in turn (long
             * evicted when it comes round again), the rest at random. */
            const size_t i = step <= (uint32_t)RSM_TMAP_TILES ? (size_t)(step - 1u)
                             : batch > 1u && b % 2u == 0u ? (next++) % (size_t)MODEL_KEYS
                                                          : (size_t)(rsm_synth_rng_next(&rng) % MODEL_KEYS);
            p[b].x = ((float)model[i].tx + 0.5f) * tile_m;
            p[b].y = ((float)model[i].ty + 0.5f) * tile_m;
            if (!model[i].held) {
                if (held == (uint32_t)RSM_TMAP_TILES) {
                    size_t j;
                    size_t oldest = MODEL_KEYS;
                    for (j = 0; j < (size_t)MODEL_KEYS; ++j) {
                        if (model[j].held && model[j].written < step &&
                            (oldest == MODEL_KEYS ||
                             model_score(&model[j], step) > model_score(&model[oldest], step) ||
                             (model_score(&model[j], step) == model_score(&model[oldest], step) &&
                              model[j].slot < model[oldest].slot))) {
                            oldest = j;
                        }
                    }
                    TEST_ASSERT_TRUE(oldest < (size_t)MODEL_KEYS);
                    model[oldest].held = 0;
                    model[i].slot = model[oldest].slot;
                    --held;
                    ++evictions;
                } else {
                    model[i].slot = held;
                }
                model[i].held = 1;
                model[i].value = 0u;
                ++held;
            }
            model[i].value = model[i].value + cfg.hit_inc > 15u ? 15u : model[i].value + cfg.hit_inc;
            model[i].written = step;
        }
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_update(&map, &o, p, n));
        most = map.counters.evicted - before > most ? map.counters.evicted - before : most;
        if (step == (uint32_t)RSM_TMAP_TILES || (step > (uint32_t)RSM_TMAP_TILES && step % 100u == 0u)) {
            model_check(step, tile_m);
        }
    }
    model_check(step, tile_m);
    TEST_ASSERT_EQUAL_UINT32(held, map.used);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)RSM_TMAP_TILES, map.used);
    TEST_ASSERT_EQUAL_UINT32(0u, map.counters.dropped);
    TEST_ASSERT_EQUAL_UINT32(evictions, map.counters.evicted);
    TEST_ASSERT_GREATER_THAN_UINT32(0u, map.counters.evicted);
    TEST_ASSERT_EQUAL_UINT32(map.counters.allocated, map.used);
    return most;
}

void test_tmap_pool_should_match_a_model_through_eviction(void)
{
    TEST_ASSERT_EQUAL_UINT32(1u, run_model(1u, 3000u));
}

void test_tmap_pool_should_match_the_model_with_many_evictions_per_write(void)
{
    TEST_ASSERT_GREATER_THAN_UINT32((uint32_t)RSM_TMAP_VICTIMS, run_model(2u * RSM_TMAP_VICTIMS + 8u, 600u));
}

void test_tmap_update_should_drop_returns_when_every_tile_is_written_by_it(void)
{
    /* One scan with returns in more tiles than the pool holds: the tiles it
     * wrote itself are never taken back, the rest is dropped and counted. */
    static rsm_point_t p[RSM_TMAP_TILES + 5];
    const float tile_m = cfg.cell_m * (float)RSM_TMAP_TILE_SIDE;
    const rsm_point_t o = {0.0f, 0.0f};
    size_t k;
    cfg.miss_dec = 0u; /* the beams near the origin would clear and free tiles */
    init();
    for (k = 0; k < (size_t)RSM_TMAP_TILES + 5u; ++k) {
        p[k].x = ((float)(k % 64u) + 0.5f) * tile_m;
        p[k].y = ((float)(k / 64u) + 0.5f) * tile_m;
    }
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_update(&map, &o, p, (size_t)RSM_TMAP_TILES + 5u));
    TEST_ASSERT_EQUAL_UINT32((uint32_t)RSM_TMAP_TILES, map.used);
    TEST_ASSERT_EQUAL_UINT32(5u, map.counters.dropped);
    TEST_ASSERT_EQUAL_UINT32(0u, map.counters.evicted);
    /* The next scan may take the oldest slots again. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_update(&map, &o, &p[RSM_TMAP_TILES], 5u));
    TEST_ASSERT_EQUAL_UINT32(5u, map.counters.evicted);
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc, rsm_tmap_value(&map, 0u, cell(p[RSM_TMAP_TILES + 4].x),
                                                        cell(p[RSM_TMAP_TILES + 4].y)));
}

void test_tmap_update_should_free_a_tile_that_beams_have_cleared(void)
{
    const uint32_t b_cell_y = (uint32_t)cell(2.05f);
    int i;
    init();
    /* Three tiles: A holds one return, B and C one each elsewhere. */
    update_one(0.05f, 0.05f, 0.55f, 0.05f);
    update_one(0.05f, 0.05f, 0.05f, 2.05f);
    update_one(0.05f, 0.05f, 0.05f, -2.05f);
    TEST_ASSERT_EQUAL_UINT32(3u, map.used);
    /* Beams through A's return to D beyond it wear it down to 0: A then
     * holds nothing and its slot goes back (D, the last slot, moves in). */
    for (i = 0; i < (int)cfg.hit_inc; ++i) {
        update_one(0.05f, 0.05f, 1.25f, 0.05f);
    }
    TEST_ASSERT_EQUAL_UINT32(1u, map.counters.freed);
    TEST_ASSERT_EQUAL_UINT32(3u, map.used);
    /* Every tile the writes began less the one freed, on each level, by
     * count and by place (rsm_tmap_t.churn). */
    {
        uint32_t level;
        for (level = 0; level < (uint32_t)cfg.levels; ++level) {
            uint32_t sig = 0;
            uint32_t k;
            for (k = 0; k < map.used; ++k) {
                if ((map.tile[k].stamp >> 30) == level) {
                    sig += rsm_tmap_place_sig(level, map.tile[k].tx, map.tile[k].ty);
                }
            }
            TEST_ASSERT_EQUAL_UINT32(rsm_tmap_tiles(&map, level), map.churn[level]);
            TEST_ASSERT_EQUAL_UINT32(sig, map.churn_sig[level]);
        }
    }
    TEST_ASSERT_EQUAL_UINT32(3u, rsm_tmap_tiles(&map, 0u));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&map, 0u, cell(0.55f), 0));
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc, rsm_tmap_value(&map, 0u, 0, (int32_t)b_cell_y));
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc, rsm_tmap_value(&map, 0u, 0, cell(-2.05f)));
    TEST_ASSERT_EQUAL_UINT8(RSM_TMAP_MAX_VALUE, rsm_tmap_value(&map, 0u, cell(1.25f), 0));
    /* The freed tile can be taken again. */
    update_one(0.05f, 0.05f, 0.05f, 0.55f);
    TEST_ASSERT_EQUAL_UINT32(4u, map.used);
    TEST_ASSERT_EQUAL_UINT32(5u, map.counters.allocated);
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc, rsm_tmap_value(&map, 0u, 0, cell(0.55f)));
}

/* Two returns on a wall 1 m ahead, then one 2 m ahead behind it. */
static void wall_and_beyond(void)
{
    update_one(0.05f, 0.05f, 1.05f, 0.05f);
    update_one(0.05f, 0.05f, 1.05f, 0.05f);
    update_one(0.05f, 0.05f, 2.05f, 0.05f);
}

void test_tmap_update_should_not_write_returns_behind_a_wall(void)
{
    TEST_ASSERT_EQUAL_UINT8(0u, cfg.wall_value); /* off by default */
    cfg.wall_value = 8u;
    init();
    /* Two returns make a wall (the cell reaches wall_value)... */
    update_one(0.05f, 0.05f, 1.05f, 0.05f);
    update_one(0.05f, 0.05f, 1.05f, 0.05f);
    TEST_ASSERT_EQUAL_UINT8(cfg.wall_value, rsm_tmap_value(&map, 0u, cell(1.05f), 0));
    /* ...that a return beyond it cannot have come through: not written, but
     * its beam still wears the wall. */
    update_one(0.05f, 0.05f, 2.05f, 0.05f);
    TEST_ASSERT_EQUAL_UINT32(1u, map.counters.behind);
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&map, 0u, cell(2.05f), 0));
    TEST_ASSERT_EQUAL_UINT8(cfg.wall_value - cfg.miss_dec, rsm_tmap_value(&map, 0u, cell(1.05f), 0));
    /* Worn below wall_value (a door opened), the wall lets returns in. */
    update_one(0.05f, 0.05f, 2.05f, 0.05f);
    TEST_ASSERT_EQUAL_UINT32(1u, map.counters.behind);
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc, rsm_tmap_value(&map, 0u, cell(2.05f), 0));
    /* A return on the wall itself (a beam grazing it first) is written. */
    update_one(0.05f, 0.05f, 1.05f, 0.05f);
    update_one(0.05f, 0.05f, 1.05f, 0.05f);
    update_one(0.05f, 0.05f, 1.05f, 0.05f);
    update_one(0.05f, 0.05f, 0.85f, 0.05f);
    update_one(0.05f, 0.05f, 0.85f, 0.05f);
    TEST_ASSERT_EQUAL_UINT8(2u * cfg.hit_inc, rsm_tmap_value(&map, 0u, cell(0.85f), 0));
    update_one(0.05f, 0.05f, 1.05f, 0.05f);
    TEST_ASSERT_EQUAL_UINT32(1u, map.counters.behind);
    /* Off: written at once. */
    cfg.wall_value = 0u;
    init();
    wall_and_beyond();
    TEST_ASSERT_EQUAL_UINT32(0u, map.counters.behind);
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc, rsm_tmap_value(&map, 0u, cell(2.05f), 0));
}

void test_tmap_update_should_write_returns_behind_a_wall_that_the_last_write_saw_too(void)
{
    TEST_ASSERT_EQUAL_UINT8(0u, cfg.wall_echo); /* off by default */
    cfg.wall_value = 8u;
    cfg.wall_echo = 1u;
    init();
    update_one(0.05f, 0.05f, 1.05f, 0.05f);
    update_one(0.05f, 0.05f, 1.05f, 0.05f);
    update_one(0.05f, 0.05f, 1.05f, 0.05f);
    /* Seen once behind the wall: refused, as without the echo rule... */
    update_one(0.05f, 0.05f, 2.05f, 0.05f);
    TEST_ASSERT_EQUAL_UINT32(1u, map.counters.behind);
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&map, 0u, cell(2.05f), 0));
    TEST_ASSERT_TRUE(rsm_tmap_value(&map, 0u, cell(1.05f), 0) >= cfg.wall_value);
    /* ...seen again by the next write (through a doorway, say): written. */
    update_one(0.05f, 0.05f, 2.05f, 0.05f);
    TEST_ASSERT_EQUAL_UINT32(1u, map.counters.behind);
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc, rsm_tmap_value(&map, 0u, cell(2.05f), 0));
    /* Only the last write counts: a return two writes later, with the wall
     * seen in between, is alone again. */
    update_one(0.05f, 0.05f, 1.05f, 0.05f);
    update_one(0.05f, 0.05f, 1.05f, 0.05f);
    update_one(0.05f, 0.05f, 2.55f, 0.05f);
    update_one(0.05f, 0.05f, 1.05f, 0.05f);
    update_one(0.05f, 0.05f, 2.55f, 0.05f);
    TEST_ASSERT_EQUAL_UINT32(3u, map.counters.behind);
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&map, 0u, cell(2.55f), 0));
}

void test_tmap_update_should_judge_walls_on_wall_level_for_every_level(void)
{
    /* Two levels, walls judged on the coarse one (no sharing of returns,
     * so that values are exact): its verdict keeps the return out of the
     * fine level too. */
    cfg.levels = 2u;
    cfg.splat_from = 2u;
    cfg.wall_level = 1u;
    cfg.wall_value = 8u;
    init();
    wall_and_beyond();
    TEST_ASSERT_EQUAL_UINT32(1u, map.counters.behind);
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&map, 0u, cell(2.05f), 0));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&map, 1u, cell(2.05f) / 2, 0));
}

/* One return at (x, y) on every level. */
static void hit_at(float x, float y)
{
    update_one(x, y + 0.5f, x, y);
}

void test_tmap_pool_should_keep_coarse_tiles_longer_with_age_shift(void)
{
    /* Region A is seen twice early (fine tiles a, a' and coarse tile A),
     * then never again; every later update sees a new region (one fine and
     * one coarse tile each) until the pool is full, and three more. With
     * age_shift 0 the oldest go whatever their level, A among them; with 2
     * a coarse tile's age counts a quarter, and younger fine tiles go
     * before A. */
    uint8_t shift;
    for (shift = 0u; shift <= 2u; shift = (uint8_t)(shift + 2u)) {
        const float ax = -1.55f;
        const int32_t a_coarse = (int32_t)floorf(ax / (2.0f * cfg.cell_m));
        uint32_t k = 0;
        uint32_t extra = 0;
        cfg.levels = 2u;
        cfg.splat_from = 2u;
        cfg.miss_dec = 0u;
        cfg.age_shift = shift;
        init();
        hit_at(ax, 0.05f);
        hit_at(-0.75f, 0.05f);
        TEST_ASSERT_EQUAL_UINT32(3u, map.used);
        while (extra < 3u) {
            if (map.used == (uint32_t)RSM_TMAP_TILES) {
                ++extra;
            }
            hit_at(0.05f + 1.6f * (float)k++, 0.05f);
        }
        TEST_ASSERT_GREATER_THAN_UINT32(4u, map.counters.evicted);
        TEST_ASSERT_EQUAL_UINT8(shift == 0u ? 0u : cfg.hit_inc, rsm_tmap_value(&map, 1u, a_coarse, 0));
        /* The fine tiles of A go first either way. */
        TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&map, 0u, cell(ax), 0));
    }
}

void test_tmap_sample_should_interpolate_and_give_the_gradient(void)
{
    int i;
    init();
    /* A short wall along y at x in cell 10 (1.0 .. 1.1 m), fully occupied. */
    for (i = 0; i < 3; ++i) {
        rsm_point_t w[5];
        const rsm_point_t o = {0.05f, 0.25f};
        size_t k;
        for (k = 0; k < 5u; ++k) {
            w[k].x = 1.05f;
            w[k].y = 0.05f + 0.1f * (float)k;
        }
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_update(&map, &o, w, 5u));
    }
    {
        float dx;
        float dy;
        float m;
        /* At the cell centre: fully occupied, flat along y. */
        m = rsm_tmap_sample(&map, 0u, 1.05f, 0.25f, &dx, &dy);
        TEST_ASSERT_FLOAT_WITHIN(1e-5f, 1.0f, m);
        TEST_ASSERT_FLOAT_WITHIN(1e-3f, 0.0f, dy);
        /* Half-way to the free cell centre in front: 0.5, rising at 1/a. */
        m = rsm_tmap_sample(&map, 0u, 1.0f, 0.25f, &dx, &dy);
        TEST_ASSERT_FLOAT_WITHIN(1e-5f, 0.5f, m);
        TEST_ASSERT_FLOAT_WITHIN(1e-3f, 1.0f / cfg.cell_m, dx);
        /* Behind the wall the slope falls. */
        m = rsm_tmap_sample(&map, 0u, 1.12f, 0.25f, &dx, &dy);
        TEST_ASSERT_FLOAT_WITHIN(1e-4f, 0.3f, m);
        TEST_ASSERT_FLOAT_WITHIN(1e-3f, -1.0f / cfg.cell_m, dx);
        /* Gradient against a finite difference at an arbitrary point. */
        {
            const float x = 1.013f;
            const float y = 0.171f;
            const float h = 1e-3f;
            float gx;
            float gy;
            float u1;
            float u2;
            (void)rsm_tmap_sample(&map, 0u, x, y, &gx, &gy);
            u1 = rsm_tmap_sample(&map, 0u, x + h, y, &dx, &dy);
            u2 = rsm_tmap_sample(&map, 0u, x - h, y, &dx, &dy);
            TEST_ASSERT_FLOAT_WITHIN(0.05f, (u1 - u2) / (2.0f * h), gx);
        }
        /* Far away: nothing. */
        m = rsm_tmap_sample(&map, 0u, -30.0f, 12.0f, &dx, &dy);
        TEST_ASSERT_EQUAL_FLOAT(0.0f, m);
        TEST_ASSERT_EQUAL_FLOAT(0.0f, dx);
        TEST_ASSERT_EQUAL_FLOAT(0.0f, dy);
    }
}

void test_tmap_bounds_should_cover_the_held_tiles(void)
{
    int32_t x0 = 0;
    int32_t y0 = 0;
    int32_t x1 = 0;
    int32_t y1 = 0;
    init();
    TEST_ASSERT_EQUAL_INT(0, rsm_tmap_bounds(&map, 0u, &x0, &y0, &x1, &y1));
    update_one(0.0f, 0.0f, -1.01f, 2.03f);
    update_one(0.0f, 0.0f, 0.42f, -0.33f);
    TEST_ASSERT_EQUAL_INT(1, rsm_tmap_bounds(&map, 0u, &x0, &y0, &x1, &y1));
    TEST_ASSERT_TRUE(x0 <= cell(-1.01f) && x1 >= cell(0.42f));
    TEST_ASSERT_TRUE(y0 <= cell(-0.33f) && y1 >= cell(2.03f));
    TEST_ASSERT_EQUAL_INT32(0, x0 % RSM_TMAP_TILE_SIDE);
    TEST_ASSERT_EQUAL_INT32(RSM_TMAP_TILE_SIDE - 1, (x1 - x0) % RSM_TMAP_TILE_SIDE);
}

/* A room's worth of returns seen from (ox, oy): a circle of radius r. */
static size_t ring(rsm_point_t *pts, size_t n, float ox, float oy, float r)
{
    size_t k;
    for (k = 0; k < n; ++k) {
        const float a = 6.2831853f * (float)k / (float)n;
        pts[k].x = ox + r * cosf(a);
        pts[k].y = oy + r * sinf(a);
    }
    return n;
}

void test_tmap_write_should_run_over_several_calls_sector_by_sector_finest_level_first(void)
{
    static rsm_tmap_t whole;
    static rsm_tmap_t before;
    static rsm_tmap_t once;
    rsm_point_t pts[90];
    const rsm_point_t o1 = {0.3f, 0.2f};
    const rsm_point_t o2 = {9.93f, -0.37f}; /* new ground; returns off cell borders */
    uint32_t calls = 0;
    uint32_t level;
    size_t n;
    size_t k;
    cfg.levels = 3u;
    init();
    whole = map;
    /* The first write at once in every map; the second whole in one... */
    n = ring(pts, 90u, o1.x, o1.y, 2.0f);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_update(&whole, &o1, pts, n));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_update(&map, &o1, pts, n));
    before = map;
    once = map;
    n = ring(pts, 90u, o2.x, o2.y, 1.7f);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_update(&whole, &o2, pts, n));
    /* ...and run without a budget in another: the same map, byte for byte. */
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_write_begin(&once, &o2, pts, n));
    TEST_ASSERT_EQUAL_INT(0, rsm_tmap_write_run(&once, pts, 0u));
    TEST_ASSERT_EQUAL_MEMORY(whole.tile, once.tile, sizeof once.tile);
    TEST_ASSERT_EQUAL_MEMORY(whole.hash, once.hash, sizeof once.hash);
    TEST_ASSERT_EQUAL_MEMORY(&whole.counters, &once.counters, sizeof once.counters);
    /* In pieces in the third. */
    TEST_ASSERT_EQUAL_INT(0, rsm_tmap_writing(&map));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_tmap_write_begin(&map, &o2, pts, n));
    TEST_ASSERT_EQUAL_INT(1, rsm_tmap_writing(&map));
    /* No second write while one runs, whole or in pieces. */
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tmap_write_begin(&map, &o2, pts, n));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_INVAL, rsm_tmap_update(&map, &o2, pts, n));
    /* A budget of one cell: one beam and its return per call, on the
     * finest level first. */
    TEST_ASSERT_EQUAL_INT(1, rsm_tmap_write_run(&map, pts, 1u));
    ++calls;
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&before, 0u, cell(pts[0].x), cell(pts[0].y)));
    TEST_ASSERT_EQUAL_UINT8(cfg.hit_inc, rsm_tmap_value(&map, 0u, cell(pts[0].x), cell(pts[0].y)));
    TEST_ASSERT_EQUAL_UINT8(0u, rsm_tmap_value(&map, 0u, cell(pts[1].x), cell(pts[1].y)));
    TEST_ASSERT_EQUAL_UINT16(before.level_used[2], map.level_used[2]);
    TEST_ASSERT_TRUE(whole.level_used[2] > before.level_used[2]);
    while (rsm_tmap_write_run(&map, pts, 1u) != 0) {
        ++calls;
        TEST_ASSERT_TRUE(calls < 1000u);
    }
    ++calls;
    TEST_ASSERT_EQUAL_UINT32(3u * (uint32_t)n, calls);
    TEST_ASSERT_EQUAL_INT(0, rsm_tmap_writing(&map));
    TEST_ASSERT_EQUAL_INT(0, rsm_tmap_write_run(&map, pts, 1u)); /* nothing left */
    /* Radial beams cross no other return of this ring: every return's cell
     * as the write at once left it, and the same tiles on every level. */
    for (k = 0; k < n; ++k) {
        TEST_ASSERT_EQUAL_UINT8(rsm_tmap_value(&whole, 0u, cell(pts[k].x), cell(pts[k].y)),
                                rsm_tmap_value(&map, 0u, cell(pts[k].x), cell(pts[k].y)));
    }
    for (level = 0; level < cfg.levels; ++level) {
        TEST_ASSERT_EQUAL_UINT16(whole.level_used[level], map.level_used[level]);
    }
    TEST_ASSERT_EQUAL_UINT32(whole.counters.updates, map.counters.updates);
}

void test_tmap_beams_crossing_should_count_beams_through_walls_beyond_the_margin(void)
{
    /* A wall of saturated cells at x = 1.05 (level 0), the robot at the
     * origin facing +x, the laser 0.1 m ahead. Returns at 2 m pass through
     * the wall; returns at 1.05 m land on it; returns at 0.9 m stop short;
     * a return 0.15 m (three cells) behind the wall counts only with a margin
     * of at most one cell: the margin's cells before the return are not
     * looked at. */
    static const rsm_pose_t pose = {0.0f, 0.0f, 0.0f};
    static const rsm_point_t laser = {0.1f, 0.0f};
    static rsm_tmap_t before;
    rsm_point_t pts[8];
    uint32_t checked = 99u;
    float y;
    size_t k;
    init();
    for (y = -0.5f; y <= 0.5f; y += 0.05f) {
        update_one(0.05f, y, 1.05f, y);
        update_one(0.05f, y, 1.05f, y);
    }
    TEST_ASSERT_TRUE(rsm_tmap_value(&map, 0u, cell(1.05f), cell(0.0f)) >= cfg.saturation);
    memcpy(&before, &map, sizeof map);
    for (k = 0; k < 8u; ++k) {
        pts[k].y = -0.3f + 0.08f * (float)k;
        pts[k].x = k < 4u ? 2.0f : k < 6u ? 1.05f : 0.9f;
    }
    TEST_ASSERT_EQUAL_UINT32(4u, rsm_tmap_beams_crossing(&map, 0u, &pose, &laser, pts, 8u, 1u, cfg.saturation, 4u,
                                                         &checked));
    TEST_ASSERT_EQUAL_UINT32(8u, checked);
    /* Every other beam: two of the four. */
    TEST_ASSERT_EQUAL_UINT32(2u, rsm_tmap_beams_crossing(&map, 0u, &pose, &laser, pts, 8u, 2u, cfg.saturation, 4u,
                                                         &checked));
    TEST_ASSERT_EQUAL_UINT32(4u, checked);
    /* Turned half a turn, the same beams point away from the wall. */
    {
        const rsm_pose_t back = {0.0f, 0.0f, 3.14159265f};
        TEST_ASSERT_EQUAL_UINT32(0u, rsm_tmap_beams_crossing(&map, 0u, &back, &laser, pts, 8u, 1u, cfg.saturation,
                                                             4u, &checked));
    }
    /* Three cells behind the wall. */
    pts[0].x = 1.2f;
    TEST_ASSERT_EQUAL_UINT32(1u, rsm_tmap_beams_crossing(&map, 0u, &pose, &laser, pts, 1u, 1u, cfg.saturation, 1u,
                                                         &checked));
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_tmap_beams_crossing(&map, 0u, &pose, &laser, pts, 1u, 1u, cfg.saturation, 3u,
                                                         &checked));
    /* Reads only; bad calls look at nothing. */
    TEST_ASSERT_EQUAL_MEMORY(&before, &map, sizeof map);
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_tmap_beams_crossing(&map, 0u, &pose, &laser, pts, 8u, 0u, cfg.saturation, 4u,
                                                         &checked));
    TEST_ASSERT_EQUAL_UINT32(0u, checked);
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_tmap_beams_crossing(&map, cfg.levels, &pose, &laser, pts, 8u, 1u,
                                                         cfg.saturation, 4u, &checked));
    TEST_ASSERT_EQUAL_UINT32(0u, rsm_tmap_beams_crossing(NULL, 0u, &pose, &laser, pts, 8u, 1u, cfg.saturation, 4u,
                                                         NULL));
}

/* The float path of rsm_tmap_read_cells' floor and fraction. */
static void float_split(float u, int32_t *i, float *frac)
{
    float fu;
    *i = (int32_t)u;
    fu = (float)*i;
    if (fu > u) {
        --*i;
        fu -= 1.0f;
    }
    *frac = u - fu;
}

static void check_split(float u)
{
    int32_t i;
    int32_t want_i;
    float frac;
    float want;
    uint32_t a;
    uint32_t b;
    float_split(u, &want_i, &want);
    if (!rsm_tmap_split(u, &i, &frac)) {
        /* only where u - floor(u) rounds, or out of the cells' range */
        TEST_ASSERT_TRUE((u < 0.0f && u > -1.0f) || fabsf(u) >= 8388608.0f);
        return;
    }
    memcpy(&a, &frac, sizeof a);
    memcpy(&b, &want, sizeof b);
    TEST_ASSERT_EQUAL_INT32(want_i, i);
    TEST_ASSERT_EQUAL_HEX32(b, a);
}

/* The soft-float cores' split of a cell coordinate on its bits equals the
 * float operations bit for bit (zeros' signs included), so that a
 * Cortex-M3 reads the map as the host does. */
void test_tmap_split_should_equal_the_float_floor_and_fraction(void)
{
    static const float edge[] = {0.0f, -0.0f, 1.0f, -1.0f, 0.5f, -0.5f, 1.5f, -1.5f, 2.0f, -2.0f, 0.999999940f,
                                 -0.999999940f, 1.00000012f, -1.00000012f, 1e-30f, -1e-30f, 1e-45f, 4194303.5f,
                                 -4194303.5f, 8388607.0f, -8388607.0f, 8388608.0f, 3.0e7f, -3.0e7f, 255.99998f,
                                 -255.99998f, 65536.0f, -65536.0f};
    uint32_t seed = 12345u;
    size_t k;
    int32_t i;
    float frac;
    for (k = 0; k < sizeof edge / sizeof edge[0]; ++k) {
        check_split(edge[k]);
    }
    /* Every exponent of the cells' range, random mantissas and signs. */
    for (k = 0; k < 200000u; ++k) {
        uint32_t bits;
        float u;
        seed = seed * 1664525u + 1013904223u;
        bits = (seed & 0x807FFFFFu) | ((uint32_t)(100u + (seed >> 8) % 52u) << 23);
        memcpy(&u, &bits, sizeof u);
        check_split(u);
    }
    TEST_ASSERT_FALSE(rsm_tmap_split(-0.25f, &i, &frac));
    TEST_ASSERT_TRUE(rsm_tmap_split(-1.25f, &i, &frac));
    TEST_ASSERT_EQUAL_INT32(-2, i);
    TEST_ASSERT_EQUAL_FLOAT(0.75f, frac);
    TEST_ASSERT_TRUE(rsm_tmap_flat(0.0f, -0.0f));
    TEST_ASSERT_FALSE(rsm_tmap_flat(0.0f, 1e-45f));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_tmap_init_should_reject_bad_configs);
    RUN_TEST(test_tmap_split_should_equal_the_float_floor_and_fraction);
    RUN_TEST(test_tmap_update_should_add_hits_and_saturate);
    RUN_TEST(test_tmap_update_should_clear_along_the_beam_but_not_near_the_return);
    RUN_TEST(test_tmap_update_should_lower_exactly_the_cells_of_bresenhams_line);
    RUN_TEST(test_tmap_update_should_take_tiles_only_for_returns);
    RUN_TEST(test_tmap_update_should_write_every_level);
    RUN_TEST(test_tmap_update_should_share_a_return_among_four_cells_on_coarse_levels);
    RUN_TEST(test_tmap_update_should_skip_non_finite_points_and_refuse_bad_arguments);
    RUN_TEST(test_tmap_pool_should_match_a_model_through_eviction);
    RUN_TEST(test_tmap_pool_should_match_the_model_with_many_evictions_per_write);
    RUN_TEST(test_tmap_update_should_drop_returns_when_every_tile_is_written_by_it);
    RUN_TEST(test_tmap_update_should_free_a_tile_that_beams_have_cleared);
    RUN_TEST(test_tmap_update_should_not_write_returns_behind_a_wall);
    RUN_TEST(test_tmap_update_should_write_returns_behind_a_wall_that_the_last_write_saw_too);
    RUN_TEST(test_tmap_update_should_judge_walls_on_wall_level_for_every_level);
    RUN_TEST(test_tmap_pool_should_keep_coarse_tiles_longer_with_age_shift);
    RUN_TEST(test_tmap_sample_should_interpolate_and_give_the_gradient);
    RUN_TEST(test_tmap_bounds_should_cover_the_held_tiles);
    RUN_TEST(test_tmap_write_should_run_over_several_calls_sector_by_sector_finest_level_first);
    RUN_TEST(test_tmap_beams_crossing_should_count_beams_through_walls_beyond_the_margin);
    return UNITY_END();
}
