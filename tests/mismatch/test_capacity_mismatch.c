/* An application compiled with other capacities than the library: this file
 * is built with -DRSM_MAX_BEAMS=200 against the default library
 * (tests/CMakeLists.txt), so each of its capacity-sized objects is of
 * another size, and its RSM_CONFIG_FINGERPRINT another value, than the
 * library's. Every function that sets up or fills such an object must
 * refuse it with RSM_ERR_CONFIG and write nothing, neither into the object
 * nor past it: each object sits in front of a guard as large as what the
 * library's larger objects could write beyond it. The functions that read
 * a scan the caller filled refuse it too, before reading it (rsm_localizer_scan
 * is not one of them yet). */
#include <string.h>

#include "rsm/rsm.h"
#include "unity.h"

#if RSM_MAX_BEAMS != 200
#error "built with -DRSM_MAX_BEAMS=200 (tests/CMakeLists.txt)"
#endif

/* Past the largest of this build's objects, more than the library's
 * objects of the same type hold beyond it (the localizer: about 4 KiB). */
#define GUARD_BYTES 16384u

/* An object of type with its guard, and a copy to compare with. */
#define GUARDED(type, name)                 \
    static struct {                         \
        type obj;                           \
        unsigned char guard[GUARD_BYTES];   \
    } name, name##_was

/* Fills g, then asserts that call is refused with RSM_ERR_CONFIG and every
 * byte of g (the object and its guard) is as it was. */
#define ASSERT_REFUSED(g, call)                                      \
    do {                                                             \
        memset(&(g), 0xA5, sizeof(g));                               \
        memcpy(&(g##_was), &(g), sizeof(g));                         \
        TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, (call));               \
        TEST_ASSERT_EQUAL_MEMORY(&(g##_was), &(g), sizeof(g));       \
    } while (0)

static int link_read(void *ctx, uint8_t *buf, size_t cap, uint32_t timeout_us)
{
    (void)ctx;
    (void)buf;
    (void)cap;
    (void)timeout_us;
    return 0;
}

static int link_write(void *ctx, const uint8_t *buf, size_t len)
{
    (void)ctx;
    (void)buf;
    return (int)len;
}

static uint64_t clock_now(void *ctx)
{
    (void)ctx;
    return 0u;
}

static const rsm_link_t link = {link_read, link_write, NULL, NULL, NULL};
static const rsm_clock_t clk = {clock_now, NULL};

void setUp(void)
{
}

void tearDown(void)
{
}

void test_scan_set_uniform_is_refused(void)
{
    /* The audit's case: 181 beams fit this build's 200, and the library's
     * layout put 142 floats past the scan. */
    GUARDED(rsm_scan_t, scan);
    ASSERT_REFUSED(scan, rsm_scan_set_uniform(&scan.obj, 181u, -1.5707964f, 0.017453292f));
}

void test_scan_trig_init_and_the_lms_conversion_are_refused(void)
{
    static rsm_lms_scan_t raw;
    GUARDED(rsm_scan_trig_t, trig);
    GUARDED(rsm_scan_t, scan);
    memset(&raw, 0, sizeof raw);
    raw.count = 181u;
    raw.step_cdeg = 100u;
    ASSERT_REFUSED(trig, rsm_scan_trig_init(&trig.obj));
    ASSERT_REFUSED(scan, rsm_sicklms_to_scan(&raw, 0u, &scan.obj));
}

void test_functions_that_read_a_scan_refuse_it(void)
{
    /* A scan the caller filled itself: the library would read it with its
     * own layout, past this build's smaller object (its count and ranges
     * lie beyond). Refused before a byte of it is read, and nothing
     * written to the outputs. */
    static rsm_scan_t scan;
    static rsm_sync_t sync;
    static rsm_scan_trig_t trig;
    const rsm_scan_limits_t lim = rsm_scan_limits_default();
    rsm_point_t pts[4];
    rsm_point_t pts_was[4];
    rsm_scan_drops_t drops;
    rsm_scan_drops_t drops_was;
    size_t i;
    scan.count = 3u;
    for (i = 0; i < 3u; ++i) {
        scan.angle_rad[i] = 0.1f * (float)i;
        scan.range_m[i] = 2.0f;
    }
    memset(pts, 0x5A, sizeof pts);
    memcpy(pts_was, pts, sizeof pts);
    memset(&drops, 0, sizeof drops);
    drops.nan = 7u;
    drops_was = drops;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_scan_to_points(&scan, &lim, pts, 4u, &drops));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_scan_to_points_cached(&scan, &lim, &trig, pts, 4u, &drops));
    TEST_ASSERT_EQUAL_INT(0, rsm_scan_reading_ok(&scan, 0u, &lim, &drops));
    TEST_ASSERT_EQUAL_MEMORY(pts_was, pts, sizeof pts);
    TEST_ASSERT_EQUAL_MEMORY(&drops_was, &drops, sizeof drops);
    TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_sync_scan(&sync, &scan));
    {
        /* The localizer's too: its report untouched, as the rest. */
        static rsm_localizer_t loc;
        rsm_localizer_report_t rep;
        rsm_localizer_report_t rep_was;
        memset(&rep, 0x5A, sizeof rep);
        memcpy(&rep_was, &rep, sizeof rep);
        TEST_ASSERT_EQUAL_INT(RSM_ERR_CONFIG, rsm_localizer_scan(&loc, &scan, &rep));
        TEST_ASSERT_EQUAL_MEMORY(&rep_was, &rep, sizeof rep);
    }
}

void test_localizer_and_sync_init_are_refused(void)
{
    /* rsm_sync_init refuses the caller before it looks at the localizer. */
    static rsm_localizer_config_t lcfg;
    static rsm_localizer_t loc;
    const rsm_sync_config_t scfg = rsm_sync_config_default();
    const rsm_pose_t x0 = {0.0f, 0.0f, 0.0f};
    GUARDED(rsm_localizer_t, l);
    GUARDED(rsm_sync_t, sync);
    lcfg = rsm_localizer_config_default();
    memset(&loc, 0, sizeof loc);
    ASSERT_REFUSED(l, rsm_localizer_init(&l.obj, &lcfg, &x0, NULL));
    ASSERT_REFUSED(sync, rsm_sync_init(&sync.obj, &loc, &scfg, NULL, NULL));
}

void test_revolution_init_is_refused(void)
{
    rsm_rev_config_t cfg;
    GUARDED(rsm_rev_t, rev);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_rev_config_default(&cfg));
    ASSERT_REFUSED(rev, rsm_rev_init(&rev.obj, &cfg));
}

void test_tile_store_init_is_refused(void)
{
    static rsm_tile_t tiles[4];
    static uint32_t index[8];
    GUARDED(rsm_tilestore_mem_t, mem);
    GUARDED(rsm_tile_store_t, store);
    ASSERT_REFUSED(mem, rsm_tilestore_mem_init(&mem.obj, tiles, 4u, index, 3u, &store_was.obj));
    ASSERT_REFUSED(store, rsm_tilestore_mem_init(&mem_was.obj, tiles, 4u, index, 3u, &store.obj));
}

void test_lms_codec_is_refused(void)
{
    static const rsm_lms_telegram_t t; /* the check comes before the telegram is read */
    GUARDED(rsm_lms_parser_t, parser);
    GUARDED(rsm_lms_scan_t, scan);
    ASSERT_REFUSED(parser, rsm_lms_parser_init(&parser.obj));
    ASSERT_REFUSED(scan, rsm_lms_decode_b0(&t, NULL, &scan.obj));
}

void test_aria_codec_is_refused(void)
{
    static const uint8_t sync0[6] = {0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00};
    static rsm_aria_parser_t p;
    static rsm_aria_packet_t pkt;
    size_t used = 0u;
    GUARDED(rsm_aria_parser_t, parser);
    GUARDED(rsm_aria_packet_t, out);
    GUARDED(rsm_aria_sync2_t, sync2);
    GUARDED(rsm_aria_sip_t, sip);
    GUARDED(rsm_aria_config_t, config);
    memset(&p, 0, sizeof p);
    memset(&pkt, 0, sizeof pkt);
    ASSERT_REFUSED(parser, rsm_aria_parser_init(&parser.obj));
    ASSERT_REFUSED(out, rsm_aria_parser_feed(&p, sync0, sizeof sync0, &used, &out.obj));
    ASSERT_REFUSED(out, rsm_aria_packet_build(&out.obj, 0x90u, sync0, sizeof sync0));
    ASSERT_REFUSED(sync2, rsm_aria_decode_sync2(&pkt, &sync2.obj));
    ASSERT_REFUSED(sip, rsm_aria_decode_sip(&pkt, &sip.obj));
    ASSERT_REFUSED(config, rsm_aria_decode_config(&pkt, &config.obj));
}

void test_drivers_are_refused(void)
{
    static rsm_p3dx_config_t p3dx_cfg;
    static rsm_sicklms_config_t lms_cfg;
    static rsm_ldlidar_config_t ld_cfg;
    static rsm_slamtec_config_t st_cfg;
    static rsm_scan_t scan;
    GUARDED(rsm_link_rx_t, rx);
    GUARDED(rsm_p3dx_t, p3dx);
    GUARDED(rsm_sicklms_t, lms);
    GUARDED(rsm_ldlidar_t, ld);
    GUARDED(rsm_slamtec_t, st);
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_p3dx_config_default(&p3dx_cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_sicklms_config_default(&lms_cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_ldlidar_config_default(&ld_cfg));
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_slamtec_config_default(&st_cfg));
    ASSERT_REFUSED(rx, rsm_link_rx_init(&rx.obj, &link, &clk, 10u, 20u));
    ASSERT_REFUSED(p3dx, rsm_p3dx_init(&p3dx.obj, &link, &clk, &p3dx_cfg));
    ASSERT_REFUSED(lms, rsm_sicklms_init(&lms.obj, &link, &clk, &lms_cfg, &scan));
    ASSERT_REFUSED(ld, rsm_ldlidar_init(&ld.obj, &link, &clk, &ld_cfg));
    ASSERT_REFUSED(st, rsm_slamtec_init(&st.obj, &link, &clk, &st_cfg));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_scan_set_uniform_is_refused);
    RUN_TEST(test_scan_trig_init_and_the_lms_conversion_are_refused);
    RUN_TEST(test_functions_that_read_a_scan_refuse_it);
    RUN_TEST(test_localizer_and_sync_init_are_refused);
    RUN_TEST(test_revolution_init_is_refused);
    RUN_TEST(test_tile_store_init_is_refused);
    RUN_TEST(test_lms_codec_is_refused);
    RUN_TEST(test_aria_codec_is_refused);
    RUN_TEST(test_drivers_are_refused);
    return UNITY_END();
}
