/* The core built without the ICP baseline (RSM_WITH_ICP 0, as firmware
 * images are): RSM_METHOD_ICP is refused with RSM_ERR_NOSYS and nothing
 * else changes; the other methods start and localise as usual. */
#include <string.h>

#include "paper/icp.h"
#include "rsm/localizer.h"
#include "rsm/status.h"
#include "synth.h"
#include "unity.h"

static rsm_localizer_t loc;
static rsm_localizer_config_t cfg;
static rsm_scan_t scan;

void setUp(void)
{
    memset(&loc, 0, sizeof loc);
    cfg = rsm_localizer_config_default();
}

void tearDown(void)
{
}

void test_this_build_has_no_icp(void)
{
    TEST_ASSERT_EQUAL_INT(0, RSM_WITH_ICP);
}

void test_icp_method_should_be_refused_with_nosys(void)
{
    const rsm_pose_t x0 = {0.0f, 0.0f, 0.0f};
    rsm_icp_t icp;
    rsm_icp_result_t res;
    rsm_point_t p = {1.0f, 2.0f};
    cfg.method = RSM_METHOD_ICP;
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_localizer_init(&loc, &cfg, &x0, NULL));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_icp_init(&icp, &cfg.icp));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_icp_set_reference(&icp, &p, 1u));
    TEST_ASSERT_EQUAL_INT(RSM_ERR_NOSYS, rsm_icp_align(&icp, &p, 1u, &x0, &res));
}

void test_other_methods_should_still_localise(void)
{
    static const rsm_method_t methods[] = {RSM_METHOD_MAP, RSM_METHOD_PAPER, RSM_METHOD_ODOMETRY};
    const rsm_synth_world_t world = rsm_synth_world_room();
    const rsm_synth_scan_config_t sc = rsm_synth_scan_config_default();
    const rsm_pose_t x0 = {0.5f, 0.2f, 0.1f};
    rsm_localizer_report_t rep;
    size_t m;
    for (m = 0; m < sizeof methods / sizeof methods[0]; ++m) {
        cfg.method = methods[m];
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_init(&loc, &cfg, &x0, NULL));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_synth_scan(&world, &x0, &sc, NULL, 1000u, &scan));
        TEST_ASSERT_EQUAL_INT(RSM_OK, rsm_localizer_scan(&loc, &scan, &rep));
        TEST_ASSERT_GREATER_THAN_UINT32(20u, rep.points);
        TEST_ASSERT_EQUAL_UINT32(1u, loc.counters.scans);
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_this_build_has_no_icp);
    RUN_TEST(test_icp_method_should_be_refused_with_nosys);
    RUN_TEST(test_other_methods_should_still_localise);
    return UNITY_END();
}
