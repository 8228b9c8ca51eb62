#include "mapflash.h"

#include <string.h>

#include "replay_data.h"
#include "rsm/geom.h"
#include "rsm/status.h"

typedef char rsm_mapflash_beams_fit[(RSM_REPLAY_BEAMS <= RSM_MAX_BEAMS) ? 1 : -1];
typedef char rsm_mapflash_scans_fit[(RSM_MAPFLASH_MAP_SCANS >= 1u) ? 1 : -1];

static int in_region(const rsm_mapflash_region_t *r, uint32_t offset, size_t len)
{
    return offset <= r->size && len <= (size_t)(r->size - offset);
}

int rsm_mapflash_write(void *ctx, uint32_t offset, const uint8_t *buf, size_t len)
{
    rsm_mapflash_region_t *r = (rsm_mapflash_region_t *)ctx;
    uint8_t *dst;
    size_t i;
    if (!in_region(r, offset, len)) {
        return -1;
    }
    dst = r->bytes + offset;
    /* Check first, so that a refused write changes nothing. */
    for (i = 0; i < len; ++i) {
        if ((uint8_t)(dst[i] & buf[i]) != buf[i]) {
            return -1;
        }
    }
    for (i = 0; i < len; ++i) {
        dst[i] = buf[i];
    }
    return 0;
}

int rsm_mapflash_read(void *ctx, uint32_t offset, uint8_t *buf, size_t len)
{
    const rsm_mapflash_region_t *r = (const rsm_mapflash_region_t *)ctx;
    if (!in_region(r, offset, len)) {
        return -1; /* past the region: a truncated map */
    }
    memcpy(buf, r->bytes + offset, len);
    return 0;
}

int rsm_mapflash_erase(rsm_mapflash_region_t *r, uint32_t len)
{
    const uint32_t pages = (len + RSM_MAPFLASH_PAGE - 1u) / RSM_MAPFLASH_PAGE;
    if (len > r->size || pages * RSM_MAPFLASH_PAGE > r->size) {
        return RSM_ERR_RANGE;
    }
    memset(r->bytes, 0xFF, (size_t)pages * RSM_MAPFLASH_PAGE);
    return RSM_OK;
}

static void put_bits(const rsm_replay_io_t *io, float f)
{
    uint32_t b;
    memcpy(&b, &f, sizeof b);
    rsm_replay_put_str(io, " ");
    rsm_replay_put_hex(io, b);
}

static void put_pose(const rsm_replay_io_t *io, const rsm_pose_t *p)
{
    put_bits(io, p->x);
    put_bits(io, p->y);
    put_bits(io, p->theta);
}

/* " name value", as the lines name their figures. */
static void put_field(const rsm_replay_io_t *io, const char *name, uint32_t value)
{
    rsm_replay_put_str(io, " ");
    rsm_replay_put_str(io, name);
    rsm_replay_put_str(io, " ");
    rsm_replay_put_dec(io, value);
}

static void put_info(const rsm_replay_io_t *io, const char *what, const rsm_mapfile_info_t *info)
{
    rsm_replay_put_str(io, what);
    put_field(io, "bytes", info->bytes);
    put_field(io, "tiles", info->tiles);
    put_field(io, "stamp", info->stamp);
    rsm_replay_put_str(io, " pose");
    put_pose(io, &info->pose);
    rsm_replay_put_str(io, "\n");
}

static void put_status(const rsm_replay_io_t *io, int rc)
{
    rsm_replay_put_str(io, rc < 0 ? "-" : "");
    rsm_replay_put_dec(io, rc < 0 ? (uint32_t)-rc : (uint32_t)rc);
    rsm_replay_put_str(io, " ");
    rsm_replay_put_str(io, rsm_strerror(rc));
}

static rsm_mapflash_result_t fail(const rsm_replay_io_t *io, const char *what, int rc)
{
    rsm_replay_put_str(io, "FAULT: ");
    rsm_replay_put_str(io, what);
    rsm_replay_put_str(io, ": ");
    put_status(io, rc);
    rsm_replay_put_str(io, "\n");
    return RSM_MAPFLASH_FAILED;
}

/* m->loc from m->cfg, its global search's grids in memory of their own
 * (RSM_GLOBAL_LEND_BYTES: fewer reads to a pose than in the memory they
 * share with a map write). */
static int start_localizer(rsm_mapflash_t *m, const rsm_pose_t *start)
{
    int rc = rsm_localizer_init(&m->loc, &m->cfg, start, NULL);
    if (rc == RSM_OK && m->cfg.method == RSM_METHOD_MAP) {
        rc = rsm_localizer_set_search_memory(&m->loc, m->search, sizeof m->search);
    }
    return rc;
}

#if RSM_MAPFLASH_STORE
typedef char rsm_mapflash_index_fits[((1u << RSM_MAPFLASH_INDEX_LOG2) * 3u >= 4u * RSM_MAPFLASH_MAX_TILES) ? 1 : -1];

/* rsm_tilestore_program_fn over the region: index word `at`, after the
 * map, as the part's word programming would write it. */
static int program_word(void *ctx, uint32_t at, uint32_t value)
{
    uint8_t b[4];
    memcpy(b, &value, sizeof b);
    return rsm_mapflash_write(ctx, RSM_MAPFLASH_INDEX_AT + 4u * at, b, sizeof b);
}

/* The flash store over the region's map and index, given to m->loc: what
 * the pool cannot hold stays in flash. Not a map (the first boot): no
 * store, and the load that follows refuses the region. */
static void attach_flash_store(rsm_mapflash_t *m, rsm_mapflash_region_t *flash)
{
    /* The map's room before the index: the store reads the map's length
     * from its header. */
    if (rsm_tilestore_rom_init(&m->rom, flash->bytes, RSM_MAPFLASH_INDEX_AT,
                               (const uint32_t *)(const void *)(flash->bytes + RSM_MAPFLASH_INDEX_AT),
                               RSM_MAPFLASH_INDEX_LOG2, m->rom_out, (uint32_t)sizeof m->rom_out, &m->store) == RSM_OK) {
        (void)rsm_localizer_set_store(&m->loc, &m->store);
    }
}

static void put_store(const rsm_replay_io_t *io, const rsm_mapflash_t *m)
{
    const rsm_tmap_counters_t *c = &m->loc.state.persistent.map.counters;
    rsm_replay_put_str(io, "T store");
    put_field(io, "held", m->store.count != NULL ? m->store.count(m->store.ctx) : 0u);
    put_field(io, "let_go", c->stored);
    put_field(io, "taken", c->fetched);
    put_field(io, "lost", c->unstored);
    rsm_replay_put_str(io, "\n");
}

/* Mapping: what the pool lets go is kept in RAM meanwhile. */
static int store_for_mapping(rsm_mapflash_t *m)
{
    int rc = rsm_tilestore_mem_init(&m->mem, m->mem_tiles, RSM_MAPFLASH_STORE_TILES, m->mem_index,
                                    RSM_MAPFLASH_INDEX_LOG2, &m->store);
    return rc == RSM_OK ? rsm_localizer_set_store(&m->loc, &m->store) : rc;
}

/* The bytes a save erases first: the map's room and the index's words. */
static uint32_t erase_bytes(const rsm_mapflash_t *m)
{
    (void)m;
    return RSM_MAPFLASH_REGION;
}

/* After the save: the index of the map's tiles, programmed after it. */
static int index_the_map(const rsm_mapflash_t *m, rsm_mapflash_region_t *flash)
{
    return rsm_tilestore_rom_build_index(flash->bytes, m->info.bytes,
                                         (const uint32_t *)(const void *)(flash->bytes + RSM_MAPFLASH_INDEX_AT),
                                         RSM_MAPFLASH_INDEX_LOG2, program_word, flash);
}
#else
/* The pool holds the whole map: no store, no index, no T line. */
static void attach_flash_store(rsm_mapflash_t *m, rsm_mapflash_region_t *flash)
{
    (void)m;
    (void)flash;
}

static void put_store(const rsm_replay_io_t *io, const rsm_mapflash_t *m)
{
    (void)io;
    (void)m;
}

static int store_for_mapping(rsm_mapflash_t *m)
{
    (void)m;
    return RSM_OK;
}

/* Only what the map needs, as a flash driver would. */
static uint32_t erase_bytes(const rsm_mapflash_t *m)
{
    return rsm_localizer_map_bytes(&m->loc);
}

static int index_the_map(const rsm_mapflash_t *m, rsm_mapflash_region_t *flash)
{
    (void)m;
    (void)flash;
    return RSM_OK;
}
#endif

/* The index of the step that brings scan `scan` (1-based); the step count
 * if none does. */
static uint32_t step_of_scan(uint32_t scan)
{
    uint32_t i;
    for (i = 0; i < rsm_replay_step_count; ++i) {
        if (rsm_replay_steps[i].scan == scan) {
            break;
        }
    }
    return i;
}

/* Puts scan `scan` (1-based) of the excerpt into m->scan. */
static void load_scan(rsm_mapflash_t *m, uint32_t scan)
{
    const rsm_replay_scan_t *sc = &rsm_replay_scans[scan - 1u];
    uint32_t b;
    for (b = 0; b < RSM_REPLAY_BEAMS; ++b) {
        m->scan.range_m[b] = (float)sc->range_cm[b] * 0.01f;
    }
    (void)rsm_scan_set_uniform(&m->scan, RSM_REPLAY_BEAMS, -RSM_PI / 2.0f, RSM_PI / (float)RSM_REPLAY_BEAMS);
    m->scan.stamp_us = sc->stamp_us;
}

/* Feeds steps from `first` on, up to the one bringing scan `last` (1-based),
 * as rsm_replay_run does; a P line after each scan. */
static void run_steps(rsm_mapflash_t *m, const rsm_replay_io_t *io, uint32_t first, uint32_t last)
{
    uint32_t i;
    for (i = first; i < rsm_replay_step_count; ++i) {
        const rsm_replay_step_t *st = &rsm_replay_steps[i];
        (void)rsm_localizer_ticks(&m->loc, st->left, st->right);
        if (st->scan != 0u && st->scan <= rsm_replay_scan_count) {
            load_scan(m, st->scan);
            (void)rsm_localizer_scan(&m->loc, &m->scan, &m->rep);
            rsm_replay_put_str(io, "P ");
            rsm_replay_put_dec(io, (uint32_t)st->scan - 1u);
            rsm_replay_put_str(io, " ");
            rsm_replay_put_dec(io, (uint32_t)m->rep.outcome);
            put_pose(io, &m->rep.pose);
            rsm_replay_put_str(io, "\n");
            if (st->scan >= last) {
                return;
            }
        }
    }
}

/* No valid map: map the first scans, save, and ask for the reboot. */
static rsm_mapflash_result_t map_and_save(rsm_mapflash_t *m, rsm_mapflash_region_t *flash, const rsm_replay_io_t *io)
{
    int rc = store_for_mapping(m);
    if (rc != RSM_OK) {
        return fail(io, "store", rc);
    }
    run_steps(m, io, 0u, RSM_MAPFLASH_MAP_SCANS);
    rc = rsm_mapflash_erase(flash, erase_bytes(m));
    if (rc != RSM_OK) {
        return fail(io, "erase", rc);
    }
    rc = rsm_localizer_save_map(&m->loc, rsm_mapflash_write, flash, &m->info);
    if (rc != RSM_OK) {
        return fail(io, "save", rc);
    }
    put_info(io, "S saved", &m->info);
    rc = index_the_map(m, flash);
    if (rc != RSM_OK) {
        return fail(io, "index", rc);
    }
    put_store(io, m);
    rsm_replay_put_str(io, RSM_MAPFLASH_NAME ": saved, resetting\n");
    return RSM_MAPFLASH_RESET;
}

/* The global search in the loaded map (rsm_localizer_global: no pose), as
 * a robot switched on somewhere in it: the localizer set up and the map
 * loaded from the region again (frozen, as for localizing), then the
 * excerpt's scans from RSM_MAPFLASH_GLOBAL_FROM on fed until a pose is
 * trusted or RSM_MAPFLASH_GLOBAL_SCANS scans. By default these are the
 * localized run's scans again, which a fresh localizer takes (the old one
 * would refuse their stamps as out of order): from the scans after them,
 * where the robot drives on down the corridor, no search proved a pose
 * within the 150 the excerpt has left. A G line per scan, its cost the
 * clock's ticks around rsm_localizer_scan (0 without a clock); then the GE
 * line. */
static rsm_mapflash_result_t global_search(rsm_mapflash_t *m, rsm_mapflash_region_t *flash,
                                           const rsm_replay_io_t *io)
{
    const rsm_pose_t start = {0.0f, 0.0f, 0.0f};
    const uint32_t from = RSM_MAPFLASH_GLOBAL_FROM;
    /* Odometry moves from the encoders' counts where the scan before was
     * taken (from the first step's for scan 1). */
    const uint32_t at = from > 1u ? step_of_scan(from - 1u) : 0u;
    uint32_t i;
    uint32_t scans = 0u;
    int trusted = 0;
    int rc = start_localizer(m, &start);
    if (rc != RSM_OK) {
        return fail(io, "init", rc);
    }
    attach_flash_store(m, flash);
    rc = rsm_localizer_load_map(&m->loc, rsm_mapflash_read, flash, &m->info);
    if (rc != RSM_OK) {
        return fail(io, "load_map", rc);
    }
    rc = rsm_localizer_global(&m->loc);
    if (rc != RSM_OK) {
        return fail(io, "global", rc);
    }
    if (at >= rsm_replay_step_count) {
        return fail(io, "no such scan in the excerpt", RSM_ERR_RANGE);
    }
    (void)rsm_localizer_ticks(&m->loc, rsm_replay_steps[at].left, rsm_replay_steps[at].right);
    for (i = from > 1u ? at + 1u : 0u; i < rsm_replay_step_count && scans < RSM_MAPFLASH_GLOBAL_SCANS && !trusted; ++i) {
        const rsm_replay_step_t *st = &rsm_replay_steps[i];
        uint32_t t0 = 0u;
        uint32_t cost = 0u;
        (void)rsm_localizer_ticks(&m->loc, st->left, st->right);
        if (st->scan == 0u || st->scan > rsm_replay_scan_count) {
            continue;
        }
        load_scan(m, st->scan);
        if (io->clock_fn != NULL) {
            t0 = io->clock_fn(io->clock_ctx);
        }
        rc = rsm_localizer_scan(&m->loc, &m->scan, &m->rep);
        if (io->clock_fn != NULL) {
            cost = io->clock_fn(io->clock_ctx) - t0; /* modulo 2^32: the counter may wrap */
        }
        if (rc != RSM_OK) {
            return fail(io, "scan", rc); /* a refused scan would time no search */
        }
        ++scans;
        /* Trusted as rsm-nav counts its first_trusted_scan: no search under
         * way and this scan's pose not a searching one. */
        trusted = !rsm_localizer_searching(&m->loc) && m->rep.outcome != RSM_SCAN_SEARCHING;
        rsm_replay_put_str(io, "G ");
        rsm_replay_put_dec(io, (uint32_t)st->scan - 1u);
        rsm_replay_put_str(io, " ");
        rsm_replay_put_dec(io, (uint32_t)m->rep.outcome);
        rsm_replay_put_str(io, " ");
        rsm_replay_put_dec(io, m->rep.search_work);
        rsm_replay_put_str(io, " ");
        rsm_replay_put_dec(io, cost);
        rsm_replay_put_str(io, "\n");
    }
    rsm_replay_put_str(io, trusted ? "GE proven 1 scans " : "GE proven 0 scans ");
    rsm_replay_put_dec(io, scans);
    rsm_replay_put_str(io, " budget ");
    rsm_replay_put_dec(io, m->cfg.global_budget);
    rsm_replay_put_str(io, " pose");
    put_pose(io, &m->rep.pose);
    rsm_replay_put_str(io, "\n");
    return RSM_MAPFLASH_DONE;
}

/* A valid map: localize in it, frozen, from where it was saved. */
static rsm_mapflash_result_t localize(rsm_mapflash_t *m, rsm_mapflash_region_t *flash, const rsm_replay_io_t *io)
{
    const uint32_t at = step_of_scan(RSM_MAPFLASH_MAP_SCANS);
    int rc;
    put_info(io, "L loaded", &m->info);
    rc = rsm_localizer_set_pose(&m->loc, &m->info.pose, NULL);
    if (rc != RSM_OK) {
        return fail(io, "set_pose", rc);
    }
    if (at >= rsm_replay_step_count) {
        return fail(io, "no such scan in the excerpt", RSM_ERR_RANGE);
    }
    /* The encoders kept their counts over the reboot: latch the mapping
     * run's last reading, so that the next step moves from it. */
    (void)rsm_localizer_ticks(&m->loc, rsm_replay_steps[at].left, rsm_replay_steps[at].right);
    run_steps(m, io, at + 1u, RSM_MAPFLASH_MAP_SCANS + RSM_MAPFLASH_LOC_SCANS);
    rsm_replay_put_str(io, "E scans ");
    rsm_replay_put_dec(io, m->loc.counters.scans);
    rsm_replay_put_str(io, " accepted ");
    rsm_replay_put_dec(io, m->loc.counters.outcome[RSM_SCAN_ACCEPTED]);
    /* Frozen: the map is as large as it was loaded. */
    rsm_replay_put_str(io, " map_bytes ");
    rsm_replay_put_dec(io, rsm_localizer_map_bytes(&m->loc));
    rsm_replay_put_str(io, "\n");
    put_store(io, m);
    if (global_search(m, flash, io) != RSM_MAPFLASH_DONE) {
        return RSM_MAPFLASH_FAILED;
    }
    rsm_replay_put_str(io, RSM_MAPFLASH_NAME ": done\n");
    return RSM_MAPFLASH_DONE;
}

rsm_mapflash_result_t rsm_mapflash_boot(rsm_mapflash_t *m, rsm_mapflash_region_t *flash, const rsm_replay_io_t *io)
{
    const rsm_pose_t start = {0.0f, 0.0f, 0.0f};
    int rc;
    rsm_replay_put_str(io, "F region ");
    rsm_replay_put_dec(io, flash->size);
    rsm_replay_put_str(io, " page ");
    rsm_replay_put_dec(io, RSM_MAPFLASH_PAGE);
    rsm_replay_put_str(io, "\n");
    if (flash->size < RSM_MAPFLASH_REGION) {
        return fail(io, "the region holds no map of this build", RSM_ERR_NOMEM);
    }
    /* The default configuration (RSM_METHOD_MAP), frozen for localizing in
     * a loaded map; load_map checks the map's cell size, levels and
     * saturation against it. */
    m->cfg = rsm_localizer_config_default();
    m->cfg.map_frozen = 1u;
    rc = start_localizer(m, &start);
    if (rc != RSM_OK) {
        return fail(io, "init", rc);
    }
    attach_flash_store(m, flash);
    rc = rsm_localizer_load_map(&m->loc, rsm_mapflash_read, flash, &m->info);
    if (rc != RSM_OK) {
        rsm_replay_put_str(io, "L refused ");
        put_status(io, rc);
        rsm_replay_put_str(io, "\n");
        /* Refused, loc is as init left it: start over mapping. */
        m->cfg.map_frozen = 0u;
        rc = start_localizer(m, &start);
        if (rc != RSM_OK) {
            return fail(io, "init", rc);
        }
        return map_and_save(m, flash, io);
    }
    return localize(m, flash, io);
}
