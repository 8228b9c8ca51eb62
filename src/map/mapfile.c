/* Saving and loading the persistent map: include/rsm/mapfile.h has the
 * contract, docs/mapfile.md the format. */
#include "rsm/mapfile.h"

#include <math.h>
#include <string.h>

#include "core/bytes.h"
#include "rsm/status.h"
#include "map/mapstate.h"
#include "map/tilemap.h"
#include "map/tmap_read.h"
#include "rsm/tilestore.h"

#define MAGIC0 'R'
#define MAGIC1 'S'
#define MAGIC2 'M'
#define MAGIC3 'M'

uint32_t rsm_crc32(uint32_t crc, const uint8_t *data, size_t len)
{
    size_t i;
    crc = ~crc;
    for (i = 0; i < len; ++i) {
        unsigned b;
        crc ^= data[i];
        /* Bitwise, no table: a map is saved or loaded at boot, and 1 KiB of
         * flash matters more on a small part than a few milliseconds. */
        for (b = 0; b < 8u; ++b) {
            crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
        }
    }
    return ~crc;
}

static void put_u32(uint8_t *p, uint32_t v)
{
    rsm_put_u16le(p, (uint16_t)(v & 0xFFFFu));
    rsm_put_u16le(p + 2, (uint16_t)(v >> 16));
}

static void put_f32(uint8_t *p, float f)
{
    uint32_t v;
    memcpy(&v, &f, sizeof v);
    put_u32(p, v);
}

static float get_f32(const uint8_t *p)
{
    const uint32_t v = rsm_get_u32le(p);
    float f;
    memcpy(&f, &v, sizeof f);
    return f;
}

static uint32_t file_bytes(uint32_t tiles)
{
    return RSM_MAPFILE_HEADER_BYTES + tiles * RSM_MAPFILE_TILE_BYTES + 4u;
}

/* Tiles of the map: the pool's and its store's. */
static uint32_t held(const rsm_tmap_t *map)
{
    return map->used + (map->store != NULL ? map->store->count(map->store->ctx) : 0u);
}

uint32_t rsm_localizer_map_bytes(const rsm_localizer_t *loc)
{
    if (!rsm_localizer_ready(loc) || loc->cfg->method != RSM_METHOD_MAP) {
        return 0u;
    }
    return file_bytes(held(&loc->state.persistent.map));
}

static void encode_header(uint8_t h[RSM_MAPFILE_HEADER_BYTES], const rsm_tmap_t *map, const rsm_pose_t *pose,
                          float fit)
{
    memset(h, 0, RSM_MAPFILE_HEADER_BYTES);
    h[0] = (uint8_t)MAGIC0;
    h[1] = (uint8_t)MAGIC1;
    h[2] = (uint8_t)MAGIC2;
    h[3] = (uint8_t)MAGIC3;
    rsm_put_u16le(h + 4, (uint16_t)RSM_MAPFILE_VERSION);
    rsm_put_u16le(h + 6, (uint16_t)RSM_MAPFILE_HEADER_BYTES);
    put_u32(h + 8, (uint32_t)(RSM_CONFIG_CAPACITY_FINGERPRINT & 0xFFFFFFFFul));
    put_f32(h + 12, map->cfg.cell_m);
    h[16] = map->cfg.levels;
    h[17] = (uint8_t)RSM_TMAP_TILE_LOG2;
    h[18] = map->cfg.saturation;
    h[19] = map->cfg.hit_inc;
    h[20] = map->cfg.miss_dec;
    h[21] = map->cfg.splat_from;
    put_u32(h + 24, held(map));
    put_u32(h + 28, map->stamp);
    put_f32(h + 32, pose->x);
    put_f32(h + 36, pose->y);
    put_f32(h + 40, pose->theta);
    put_f32(h + 44, fit);
}

static void encode_tile(uint8_t b[RSM_MAPFILE_TILE_BYTES], const rsm_tile_t *t)
{
    rsm_put_u16le(b, (uint16_t)t->tx);
    rsm_put_u16le(b + 2, (uint16_t)t->ty);
    put_u32(b + 4, t->stamp);
    memcpy(b + 8, t->cell, sizeof t->cell);
}

void rsm_mapfile_decode_tile(rsm_tile_t *t, const uint8_t *b)
{
    t->tx = (int16_t)rsm_get_u16le(b);
    t->ty = (int16_t)rsm_get_u16le(b + 2);
    t->stamp = rsm_get_u32le(b + 4);
    memcpy(t->cell, b + 8, sizeof t->cell);
}

/* The fit a map is saved with: the recent scans', unless the map was
 * loaded and has not changed since (frozen): then the one it came with, as
 * a lost run over it says nothing of the map. */
static float saved_fit(const rsm_localizer_t *loc)
{
    const float loaded = loc->state.persistent.map_fit;
    return loc->cfg->map_frozen && loaded > 0.0f ? loaded : loc->state.persistent.fit;
}

int rsm_localizer_save_map(const rsm_localizer_t *loc, rsm_mapfile_write_fn write, void *ctx,
                           rsm_mapfile_info_t *info)
{
    const rsm_tmap_t *map;
    uint8_t buf[RSM_MAPFILE_TILE_BYTES > RSM_MAPFILE_HEADER_BYTES ? RSM_MAPFILE_TILE_BYTES
                                                                   : RSM_MAPFILE_HEADER_BYTES];
    uint32_t crc;
    uint32_t at;
    uint32_t s;
    uint32_t tiles;
    if (!rsm_localizer_ready(loc) || write == NULL) {
        return RSM_ERR_INVAL;
    }
    if (loc->cfg->method != RSM_METHOD_MAP) {
        return RSM_ERR_NOSYS;
    }
    map = &loc->state.persistent.map;
    encode_header(buf, map, &loc->ekf.x, saved_fit(loc));
    if (write(ctx, 0u, buf, RSM_MAPFILE_HEADER_BYTES) != 0) {
        return RSM_ERR_IO;
    }
    crc = rsm_crc32(0u, buf, RSM_MAPFILE_HEADER_BYTES);
    at = RSM_MAPFILE_HEADER_BYTES;
    tiles = held(map);
    /* The pool's tiles first: a load fills the pool with them. */
    for (s = 0; s < tiles; ++s) {
        rsm_tile_t stored;
        const rsm_tile_t *t = &stored;
        if (s < map->used) {
            t = &map->tile[s];
        } else if (map->store->at(map->store->ctx, s - map->used, &stored) != RSM_OK) {
            return RSM_ERR_IO;
        }
        encode_tile(buf, t);
        if (write(ctx, at, buf, RSM_MAPFILE_TILE_BYTES) != 0) {
            return RSM_ERR_IO;
        }
        crc = rsm_crc32(crc, buf, RSM_MAPFILE_TILE_BYTES);
        at += RSM_MAPFILE_TILE_BYTES;
    }
    put_u32(buf, crc);
    if (write(ctx, at, buf, 4u) != 0) {
        return RSM_ERR_IO;
    }
    if (info != NULL) {
        info->bytes = at + 4u;
        info->tiles = tiles;
        info->stamp = map->stamp;
        info->pose = loc->ekf.x;
        info->fit = saved_fit(loc);
    }
    return RSM_OK;
}

/* The header's verdict against loc's configuration and room (tiles the
 * pool and its store hold at most); fills *info. */
static int check_header(const uint8_t h[RSM_MAPFILE_HEADER_BYTES], const rsm_tmap_config_t *cfg, uint32_t room,
                        rsm_mapfile_info_t *info)
{
    const float cell = get_f32(h + 12);
    if (h[0] != (uint8_t)MAGIC0 || h[1] != (uint8_t)MAGIC1 || h[2] != (uint8_t)MAGIC2 || h[3] != (uint8_t)MAGIC3 ||
        rsm_get_u16le(h + 4) != RSM_MAPFILE_VERSION || rsm_get_u16le(h + 6) != RSM_MAPFILE_HEADER_BYTES ||
        rsm_get_u32le(h + 8) != (uint32_t)(RSM_CONFIG_CAPACITY_FINGERPRINT & 0xFFFFFFFFul)) {
        return RSM_ERR_FORMAT;
    }
    /* Exactly the cell size in use: a map of other cells would be read at
     * the wrong scale. */
    if (memcmp(&cell, &cfg->cell_m, sizeof cell) != 0 || h[16] != cfg->levels ||
        h[17] != (uint8_t)RSM_TMAP_TILE_LOG2 || h[18] != cfg->saturation) {
        return RSM_ERR_FORMAT;
    }
    info->tiles = rsm_get_u32le(h + 24);
    info->stamp = rsm_get_u32le(h + 28);
    info->pose.x = get_f32(h + 32);
    info->pose.y = get_f32(h + 36);
    info->pose.theta = get_f32(h + 40);
    info->fit = get_f32(h + 44);
    if (info->tiles > room ||
        info->tiles > (0xFFFFFFFFu - RSM_MAPFILE_HEADER_BYTES - 4u) / RSM_MAPFILE_TILE_BYTES || info->stamp > RSM_TMAP_STAMP_MASK ||
        !(info->fit >= 0.0f && info->fit <= 1.0f) || !isfinite(info->pose.x) || !isfinite(info->pose.y) ||
        !isfinite(info->pose.theta)) {
        return RSM_ERR_FORMAT;
    }
    info->bytes = file_bytes(info->tiles);
    return RSM_OK;
}

#define ALL_LEVELS 0xFFu

/* A tile into the pool while it has room, then into the store; a place
 * held twice is RSM_ERR_FORMAT. */
static int restore(rsm_tmap_t *map, const rsm_tile_t *t)
{
    if (map->used < (uint32_t)RSM_TMAP_TILES || map->store == NULL) {
        return rsm_tmap_restore(map, t);
    }
    if (rsm_tmap_find_slot(map, t->stamp >> 30, t->tx, t->ty) != RSM_TMAP_NONE) {
        return RSM_ERR_FORMAT;
    }
    switch (map->store->put(map->store->ctx, t)) {
    case RSM_OK:
        return RSM_OK;
    case RSM_ERR_NOMEM:
        return RSM_ERR_NOMEM;
    default:
        return RSM_ERR_FORMAT;
    }
}

/* One pass over a stored map: checks it against map, and with into != NULL
 * (map itself, emptied, its stamp set) restores its tiles of the given level
 * (ALL_LEVELS: every one) there, those the pool cannot hold into its
 * store. RSM_OK or the first fault found. */
static int read_pass(rsm_mapfile_read_fn read, void *ctx, const rsm_tmap_t *map, rsm_tmap_t *into,
                     uint32_t level, rsm_mapfile_info_t *info)
{
    uint8_t buf[RSM_MAPFILE_TILE_BYTES > RSM_MAPFILE_HEADER_BYTES ? RSM_MAPFILE_TILE_BYTES
                                                                   : RSM_MAPFILE_HEADER_BYTES];
    uint32_t crc;
    uint32_t at;
    uint32_t k;
    int rc;
    const rsm_tmap_config_t *cfg = &map->cfg;
    const uint32_t room = (uint32_t)RSM_TMAP_TILES + (map->store != NULL ? map->store->capacity : 0u);
    if (read(ctx, 0u, buf, RSM_MAPFILE_HEADER_BYTES) != 0) {
        return RSM_ERR_IO;
    }
    if ((rc = check_header(buf, cfg, room, info)) != RSM_OK) {
        return rc;
    }
    crc = rsm_crc32(0u, buf, RSM_MAPFILE_HEADER_BYTES);
    at = RSM_MAPFILE_HEADER_BYTES;
    for (k = 0; k < info->tiles; ++k) {
        rsm_tile_t t;
        if (read(ctx, at, buf, RSM_MAPFILE_TILE_BYTES) != 0) {
            return RSM_ERR_IO;
        }
        crc = rsm_crc32(crc, buf, RSM_MAPFILE_TILE_BYTES);
        at += RSM_MAPFILE_TILE_BYTES;
        rsm_mapfile_decode_tile(&t, buf);
        /* What can be checked of a tile alone is checked in both passes;
         * a place held twice only shows in the second. */
        if ((t.stamp >> 30) >= (uint32_t)cfg->levels || (t.stamp & RSM_TMAP_STAMP_MASK) > info->stamp ||
            t.tx <= -RSM_TMAP_TILE_LIMIT || t.tx >= RSM_TMAP_TILE_LIMIT || t.ty <= -RSM_TMAP_TILE_LIMIT ||
            t.ty >= RSM_TMAP_TILE_LIMIT) {
            return RSM_ERR_FORMAT;
        }
        if (into != NULL && (level == ALL_LEVELS || (t.stamp >> 30) == level) && (rc = restore(into, &t)) != RSM_OK) {
            return rc;
        }
    }
    if (read(ctx, at, buf, 4u) != 0) {
        return RSM_ERR_IO;
    }
    return rsm_get_u32le(buf) == crc ? RSM_OK : RSM_ERR_CHECKSUM;
}

int rsm_localizer_load_map(rsm_localizer_t *loc, rsm_mapfile_read_fn read, void *ctx, rsm_mapfile_info_t *info)
{
    rsm_mapfile_info_t got;
    rsm_tmap_t *map;
    int rc;
    if (!rsm_localizer_ready(loc) || read == NULL) {
        return RSM_ERR_INVAL;
    }
    if (loc->cfg->method != RSM_METHOD_MAP) {
        return RSM_ERR_NOSYS;
    }
    map = &loc->state.persistent.map;
    if ((rc = read_pass(read, ctx, map, NULL, ALL_LEVELS, &got)) != RSM_OK) {
        return rc;
    }
    rsm_tmap_reset(map);
    map->stamp = got.stamp;
    if (got.tiles <= (uint32_t)RSM_TMAP_TILES) {
        rc = read_pass(read, ctx, map, map, ALL_LEVELS, &got);
    } else {
        /* More than the pool holds (the rest goes to the store): the
         * coarse levels first, a pass each, so that the pool holds the
         * whole building's outline, which the global search reads, and
         * the fine detail comes back from the store where the robot is. */
        uint32_t level = map->cfg.levels;
        rc = RSM_OK;
        while (rc == RSM_OK && level-- > 0u) {
            rc = read_pass(read, ctx, map, map, level, &got);
        }
    }
    if (rc != RSM_OK) {
        rsm_tmap_reset(map);
        rsm_localizer_map_cleared(loc);
        return rc;
    }
    rsm_localizer_map_replaced(loc, got.fit);
    if (info != NULL) {
        *info = got;
    }
    return RSM_OK;
}
