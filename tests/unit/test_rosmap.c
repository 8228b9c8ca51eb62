/* The ROS map reader of rsm-nav (tools/nav/rosmap.c): the handmade fixture
 * in tests/data/rosmap (a P2 room at 10 cm) lands where its YAML says, top
 * row at the top; negate, raw mode, P5, quotes and comments are read as
 * map_server reads them; every malformed map (generated here) is refused
 * with a message that names the fault, and the localizer left as it was;
 * a map larger than the pool goes in incomplete, and says so. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rosmap.h"
#include "rsm/config.h"
#include "rsm/localizer.h"
#include "rsm/mapimport.h"
#include "rsm/status.h"
#include "map/tilemap.h"
#include "unity.h"

#define FIXTURE RSM_SOURCE_DIR "/tests/data/rosmap/room.yaml"
#define YAML "rosmap_test.yaml"
#define PGM "rosmap_test.pgm"

static rsm_localizer_t loc;
static rsm_localizer_t before;
static rsm_localizer_config_t cfg;
static char err[512];
static const rsm_pose_t origin = {0.0f, 0.0f, 0.0f};

void setUp(void)
{
    cfg = rsm_localizer_config_default();
    cfg.map_frozen = 1u;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &cfg, &origin, NULL));
    err[0] = '\0';
}

void tearDown(void)
{
    (void)remove(YAML);
    (void)remove(PGM);
}

static void write_file(const char *path, const void *bytes, size_t len)
{
    FILE *f = fopen(path, "wb");
    TEST_ASSERT_NOT_NULL(f);
    TEST_ASSERT_EQUAL_size_t(len, fwrite(bytes, 1, len, f));
    TEST_ASSERT_EQUAL_INT(0, fclose(f));
}

static void write_text(const char *path, const char *text)
{
    write_file(path, text, strlen(text));
}

static float occ_at(float x, float y)
{
    return rsm_tmap_occupancy(&loc.state.persistent.map, 0u, x, y);
}

/* Occupied at the pixel whose centre is (x, y): both finest cells either
 * side of its centre (pixels of 10 cm, cells of at most 10 cm). */
static int pixel_occupied(float x, float y)
{
    const float d = 0.3f * cfg.tmap.cell_m;
    return occ_at(x - d, y - d) > 0.0f && occ_at(x + d, y + d) > 0.0f;
}

static void test_fixture_lands_where_its_yaml_says(void)
{
    rsm_import_report_t rep;
    TEST_ASSERT_EQUAL_INT_MESSAGE(0, rsm_rosmap_load(FIXTURE, &loc, &rep, err, sizeof err), err);
    TEST_ASSERT_EQUAL_UINT32(24u, rep.rows);
    /* Walls 28 + 28 + 18 + 18, a 2 x 2 pillar, one dark mark; the faint
     * mark (p 0.61 < occupied_thresh 0.65) is not a wall. */
    TEST_ASSERT_EQUAL_UINT32(97u, rep.occupied);
    TEST_ASSERT_EQUAL_UINT32(0u, rep.dropped);
    /* PGM column c, row r from the top: centre (-1.6 + (c + 0.5) 0.1,
     * -1.2 + (23 - r + 0.5) 0.1). The pillar (rows 5-6, columns 6-7) is
     * near the top, not mirrored to the bottom. */
    TEST_ASSERT_TRUE(pixel_occupied(-0.95f, 0.65f));
    TEST_ASSERT_TRUE(pixel_occupied(-0.85f, 0.55f));
    TEST_ASSERT_FALSE(pixel_occupied(-0.95f, -0.65f));
    /* The walls: row 2 (y 0.95), row 21 (y -0.95), column 2 (x -1.35),
     * column 29 (x 1.35). */
    TEST_ASSERT_TRUE(pixel_occupied(0.05f, 0.95f));
    TEST_ASSERT_TRUE(pixel_occupied(0.05f, -0.95f));
    TEST_ASSERT_TRUE(pixel_occupied(-1.35f, 0.05f));
    TEST_ASSERT_TRUE(pixel_occupied(1.35f, 0.05f));
    /* Free inside, unknown outside: nothing. */
    TEST_ASSERT_EQUAL_FLOAT(0.0f, occ_at(0.0f, 0.0f));
    TEST_ASSERT_EQUAL_FLOAT(0.0f, occ_at(-1.55f, 1.15f));
    /* The dark mark (row 15, column 24) is a wall, the faint one (column
     * 20) is not. */
    TEST_ASSERT_TRUE(pixel_occupied(0.85f, -0.35f));
    TEST_ASSERT_FALSE(pixel_occupied(0.45f, -0.35f));
    /* The next scan is matched against it. */
    TEST_ASSERT_EQUAL_UINT8(1u, loc.have_scan);
}

/* A 4 x 2 P5 image with the given pixels (top row first). */
static void write_p5(const unsigned char px[8])
{
    unsigned char b[64];
    const char *h = "P5\n# two rows\n4 2\n255\n";
    const size_t n = strlen(h);
    memcpy(b, h, n);
    memcpy(b + n, px, 8);
    write_file(PGM, b, n + 8u);
}

static uint32_t occupied_of(const char *yaml)
{
    rsm_import_report_t rep;
    write_text(YAML, yaml);
    TEST_ASSERT_EQUAL_INT_MESSAGE(0, rsm_rosmap_load("./" YAML, &loc, &rep, err, sizeof err), err);
    return rep.occupied;
}

static void test_negate_raw_and_scale_modes(void)
{
    static const unsigned char px[8] = {0, 50, 89, 90, 100, 101, 200, 255};
    write_p5(px);
    /* p = (255 - v) / 255 > 0.65: v < 89.25: 0, 50, 89. */
    TEST_ASSERT_EQUAL_UINT32(3u, occupied_of("image: " PGM "\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
                                             "occupied_thresh: 0.65\nfree_thresh: 0.196\n"));
    /* The same under scale: only above occupied_thresh is a wall. */
    TEST_ASSERT_EQUAL_UINT32(3u, occupied_of("image: " PGM "\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
                                             "occupied_thresh: 0.65\nfree_thresh: 0.196\nmode: scale\n"));
    /* negate: p = v / 255 > 0.65: v > 165.75: 200, 255. */
    TEST_ASSERT_EQUAL_UINT32(2u, occupied_of("image: " PGM "\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 1\n"
                                             "occupied_thresh: 0.65\nfree_thresh: 0.196\n"));
    /* raw: v <= 100 and v / 100 > 0.65: 89, 90, 100. */
    TEST_ASSERT_EQUAL_UINT32(3u, occupied_of("image: " PGM "\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
                                             "occupied_thresh: 0.65\nfree_thresh: 0.196\nmode: raw\n"));
    /* Quotes, comments, blank lines, a document marker and another tool's
     * key are read as YAML. */
    TEST_ASSERT_EQUAL_UINT32(3u, occupied_of("---\n# saved by hand\nimage: \"" PGM "\"  # the picture\n\n"
                                             "resolution: 0.05\norigin: [ 0.0 , 0.0 , 0.0 ]\nnegate: false\n"
                                             "occupied_thresh: '0.65'\nfree_thresh: 0.196\nsaved_by: someone\n"));
}

/* A map placed by its origin and turned by its yaw. */
static void test_origin_and_yaw(void)
{
    static const unsigned char px[8] = {255, 255, 255, 255, 0, 255, 255, 255};
    const float d = 0.3f * cfg.tmap.cell_m;
    write_p5(px);
    /* Bottom row, pixel 0: centre (2 + 0.1, -1 + 0.1) at 0.2 m. */
    TEST_ASSERT_EQUAL_UINT32(1u, occupied_of("image: " PGM "\nresolution: 0.2\norigin: [2.0, -1.0, 0.0]\n"
                                             "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"));
    TEST_ASSERT_TRUE(occ_at(2.1f - d, -0.9f - d) > 0.0f && occ_at(2.1f + d, -0.9f + d) > 0.0f);
    /* Turned a quarter turn about the origin: (0.1, 0.1) goes to (-0.1, 0.1). */
    TEST_ASSERT_EQUAL_UINT32(1u, occupied_of("image: " PGM "\nresolution: 0.2\norigin: [2.0, -1.0, 1.5707963]\n"
                                             "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"));
    TEST_ASSERT_TRUE(occ_at(1.9f - d, -0.9f - d) > 0.0f && occ_at(1.9f + d, -0.9f + d) > 0.0f);
    TEST_ASSERT_EQUAL_FLOAT(0.0f, occ_at(2.1f, -0.9f));
}

/* Each malformed map: -1, a message holding `says`, loc unchanged. */
static void refused(const char *yaml, const char *says)
{
    char msg[700];
    int rc;
    if (yaml != NULL) {
        write_text(YAML, yaml);
    }
    before = loc;
    rc = rsm_rosmap_load(YAML, &loc, NULL, err, sizeof err);
    (void)snprintf(msg, sizeof msg, "want '%s', got %d '%s'", says, rc, err);
    TEST_ASSERT_EQUAL_INT_MESSAGE(-1, rc, msg);
    TEST_ASSERT_NOT_NULL_MESSAGE(strstr(err, says), msg);
    TEST_ASSERT_EQUAL_MEMORY_MESSAGE(&before, &loc, sizeof loc, msg);
}

#define GOOD_TAIL "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"

static void test_malformed_yaml_refused(void)
{
    static const unsigned char px[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    char err0[8];
    write_p5(px);
    /* A map in place first: a refused one must leave it. */
    TEST_ASSERT_EQUAL_INT_MESSAGE(0, rsm_rosmap_load(FIXTURE, &loc, NULL, err, sizeof err), err);
    refused("resolution: 0.05\norigin: [0, 0, 0]\n" GOOD_TAIL, "no 'image:' key");
    refused("image: " PGM "\norigin: [0, 0, 0]\n" GOOD_TAIL, "no 'resolution:' key");
    refused("image: " PGM "\nresolution: 0.05\n" GOOD_TAIL, "no 'origin:' key");
    refused("image: " PGM "\nresolution: 0.05\norigin: [0, 0, 0]\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
            "no 'negate:' key");
    refused("image: " PGM "\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\nfree_thresh: 0.196\n",
            "no 'occupied_thresh:' key");
    refused("image: " PGM "\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\n",
            "no 'free_thresh:' key");
    refused("image: " PGM "\nresolution: 5cm\norigin: [0, 0, 0]\n" GOOD_TAIL, "resolution '5cm'");
    refused("image: " PGM "\nresolution: -0.05\norigin: [0, 0, 0]\n" GOOD_TAIL, "resolution '-0.05'");
    refused("image: " PGM "\nresolution: 0\norigin: [0, 0, 0]\n" GOOD_TAIL, "resolution '0'");
    refused("image: " PGM "\nresolution: nan\norigin: [0, 0, 0]\n" GOOD_TAIL, "resolution 'nan'");
    refused("image: " PGM "\nresolution: 0.05\norigin: [0, 0]\n" GOOD_TAIL, "origin is not");
    refused("image: " PGM "\nresolution: 0.05\norigin: [0, 0, 0, 0]\n" GOOD_TAIL, "origin is not");
    refused("image: " PGM "\nresolution: 0.05\norigin: [0, x, 0]\n" GOOD_TAIL, "origin is not");
    refused("image: " PGM "\nresolution: 0.05\norigin: 0, 0, 0\n" GOOD_TAIL, "origin is not");
    refused("image: " PGM "\nresolution: 0.05\norigin: [0, 1e39, 0]\n" GOOD_TAIL, "out of range");
    refused("image: " PGM "\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 2\noccupied_thresh: 0.65\n"
            "free_thresh: 0.196\n",
            "negate '2'");
    refused("image: " PGM "\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 1.5\n"
            "free_thresh: 0.196\n",
            "occupied_thresh '1.5'");
    refused("image: " PGM "\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.1\n"
            "free_thresh: 0.196\n",
            "free_thresh 0.196 is not below occupied_thresh 0.1");
    refused("image: " PGM "\nresolution: 0.05\norigin: [0, 0, 0]\n" GOOD_TAIL "mode: ternary\n", "mode 'ternary'");
    refused("image: " PGM "\nresolution: 0.05\nresolution: 0.1\norigin: [0, 0, 0]\n" GOOD_TAIL,
            "resolution given twice");
    refused("image: " PGM "\nresolution 0.05\norigin: [0, 0, 0]\n" GOOD_TAIL, ":2: not a 'key: value' line");
    refused("image: '" PGM "\nresolution: 0.05\norigin: [0, 0, 0]\n" GOOD_TAIL, "unclosed quote");
    refused("image: " PGM "\nresolution: 100\norigin: [0, 0, 0]\n" GOOD_TAIL, "more than 256");
    refused("image: no_such_map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n" GOOD_TAIL, "cannot open image");
    (void)remove(YAML);
    refused(NULL, "cannot open map YAML");
    /* No room for the message: still refused, nothing written. */
    write_text(YAML, "resolution: 0.05\n");
    memset(err0, 'x', sizeof err0);
    TEST_ASSERT_EQUAL_INT(-1, rsm_rosmap_load(YAML, &loc, NULL, err0, 0u));
    TEST_ASSERT_EQUAL_INT('x', err0[0]);
}

static const char *const ok_yaml = "image: " PGM "\nresolution: 0.05\norigin: [0, 0, 0]\n" GOOD_TAIL;

static void refused_pgm(const void *bytes, size_t len, const char *says)
{
    write_file(PGM, bytes, len);
    refused(ok_yaml, says);
}

/* A literal's bytes without its terminating NUL. */
#define REFUSED_PGM(lit, says) refused_pgm(lit, sizeof lit - 1u, says)

static void test_malformed_pgm_refused(void)
{
    static const char p5_ok[] = "P5\n4 2\n255\n\0\0\0\0\0\0\0\0";
    TEST_ASSERT_EQUAL_INT_MESSAGE(0, rsm_rosmap_load(FIXTURE, &loc, NULL, err, sizeof err), err);
    /* The good one first: the cases below differ from it in one way. */
    write_file(PGM, p5_ok, sizeof p5_ok - 1u);
    write_text(YAML, ok_yaml);
    before = loc;
    TEST_ASSERT_EQUAL_INT_MESSAGE(0, rsm_rosmap_load(YAML, &loc, NULL, err, sizeof err), err);
    loc = before;
    refused_pgm(p5_ok, sizeof p5_ok - 2u, "truncated: 7 of 8 pixel bytes (row 2 of 2 is short");
    REFUSED_PGM("P5\n4 2\n255\n", "truncated: 0 of 8");
    REFUSED_PGM("P5\n4 2\n255", "truncated: no pixel data");
    REFUSED_PGM("P5\n4 2\n", "header ends early");
    REFUSED_PGM("P5\n4 2\n255\n\0\0\0\0\0\0\0\0\0", "1 bytes after the last row");
    REFUSED_PGM("P5\n4 2\n65535\n\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0", "16-bit PGM (maxval 65535)");
    REFUSED_PGM("P5\n4 2\n0\n\0\0\0\0\0\0\0\0", "maxval must be");
    REFUSED_PGM("P5\n4 2\n100\n\0\0\0\0\0\0\0\xC8", "pixel 3 of row 1 is 200, above maxval 100");
    REFUSED_PGM("P5\n0 2\n255\n", "width and height");
    REFUSED_PGM("P5\n4 x\n255\n\0\0\0\0\0\0\0\0", "width and height");
    REFUSED_PGM("P6\n4 2\n255\n\0\0\0\0\0\0\0\0", "another netpbm kind");
    REFUSED_PGM("\x89PNG\r\n\x1a\n", "no P5/P2 magic");
    REFUSED_PGM("", "no P5/P2 magic");
    REFUSED_PGM("P2\n4 2\n255\n0 0 0 0\n0 0 0\n", "truncated: 7 of 8 pixels (row 2 of 2 is short");
    REFUSED_PGM("P2\n4 2\n255\n0 0 0 0\n0 0 0 0 0\n", "data after the last pixel");
    REFUSED_PGM("P2\n4 2\n255\n0 0 0 0\n0 0 256 0\n", "pixel 2 of row 1 is not a number");
    REFUSED_PGM("P2\n4 2\n255\n0 0 0 0\n0 0 -1 0\n", "pixel 2 of row 1 is not a number");
    REFUSED_PGM("P2\n4 2\n300\n0 0 0 0\n0 0 0 0\n", "16-bit PGM (maxval 300)");
    REFUSED_PGM("P2\n4 2\n70000\n0 0 0 0\n0 0 0 0\n", "maxval 70000 is beyond 65535");
    /* All free: no wall to localize against. */
    REFUSED_PGM("P5\n4 2\n255\n\xFF\xFF\xFF\xFF\xFF\xFF\xFF\xFF", "no occupied pixel");
}

/* Other localizers: refused before anything is read into them. */
static void test_other_method_refused(void)
{
    cfg.method = RSM_METHOD_ODOMETRY;
    TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &cfg, &origin, NULL));
    before = loc;
    TEST_ASSERT_EQUAL_INT(-1, rsm_rosmap_load(FIXTURE, &loc, NULL, err, sizeof err));
    TEST_ASSERT_NOT_NULL_MESSAGE(strstr(err, "only for the map method"), err);
    TEST_ASSERT_EQUAL_MEMORY(&before, &loc, sizeof loc);
    TEST_ASSERT_EQUAL_INT(-1, rsm_rosmap_load(NULL, &loc, NULL, err, sizeof err));
    TEST_ASSERT_EQUAL_INT(-1, rsm_rosmap_load(FIXTURE, NULL, NULL, err, sizeof err));
}

/* More walls than the pool holds: imported as far as they fit, return 1,
 * and the message says how much was lost. */
static void test_pool_full_says_incomplete(void)
{
    const uint32_t side = 1200u;
    const char *h = "P5\n1200 1200\n255\n";
    const size_t hn = strlen(h);
    unsigned char *b = (unsigned char *)malloc(hn + (size_t)side * side);
    rsm_import_report_t rep;
    uint32_t k;
    TEST_ASSERT_NOT_NULL(b);
    memcpy(b, h, hn);
    for (k = 0; k < side * side; ++k) {
        /* A wall pixel every fourth in both directions: every tile held. */
        b[hn + k] = (k % side) % 4u == 0u && (k / side) % 4u == 0u ? 0u : 254u;
    }
    write_file(PGM, b, hn + (size_t)side * side);
    free(b);
    write_text(YAML, ok_yaml);
    TEST_ASSERT_EQUAL_INT_MESSAGE(1, rsm_rosmap_load(YAML, &loc, &rep, err, sizeof err), err);
    TEST_ASSERT_TRUE(rep.dropped > 0u);
    TEST_ASSERT_EQUAL_UINT32(side, rep.rows);
    TEST_ASSERT_EQUAL_UINT32(300u * 300u, rep.occupied);
    TEST_ASSERT_NOT_NULL_MESSAGE(strstr(err, "imported incomplete"), err);
    TEST_ASSERT_NOT_NULL_MESSAGE(strstr(err, "pool"), err);
    TEST_ASSERT_EQUAL_UINT32((uint32_t)RSM_TMAP_TILES, loc.state.persistent.map.used);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_fixture_lands_where_its_yaml_says);
    RUN_TEST(test_negate_raw_and_scale_modes);
    RUN_TEST(test_origin_and_yaw);
    RUN_TEST(test_malformed_yaml_refused);
    RUN_TEST(test_malformed_pgm_refused);
    RUN_TEST(test_other_method_refused);
    RUN_TEST(test_pool_full_says_incomplete);
    return UNITY_END();
}
