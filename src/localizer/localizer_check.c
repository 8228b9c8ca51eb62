/* Validation of rsm_localizer_config_t, naming the first bad field: what
 * rsm_localizer_init refuses with RSM_ERR_INVAL (include/rsm/localizer.h). */
#include "rsm/localizer.h"

#include <math.h>

#include "rsm/status.h"
#include "core/check.h"
#include "paper/icp.h"
#include "map/mapmatch.h"
#include "paper/ransac.h"
#include "map/tilemap.h"

/* The method's own part: each method uses (and so checks) only its own. */
static int check_method_part(const rsm_localizer_config_t *cfg, const char **field)
{
    switch (cfg->method) {
    case RSM_METHOD_PAPER:
        return rsm_ransac_config_check(&cfg->ransac, field);
    case RSM_METHOD_ICP:
        return rsm_icp_config_check(&cfg->icp, field);
    case RSM_METHOD_MAP:
        /* The map's and the matcher's first: recover_m and recover_rad are
         * bounded by their cells and steps. */
        if (rsm_tmap_config_check(&cfg->tmap, field) != RSM_OK) {
            return RSM_ERR_INVAL;
        }
        RSM_CHECK_FIELD(rsm_mapmatch_check(&cfg->mapmatch) == RSM_OK, "mapmatch");
        RSM_CHECK_FIELD(cfg->map_update_m >= 0.0f, "map_update_m");
        RSM_CHECK_FIELD(cfg->map_update_rad >= 0.0f, "map_update_rad");
        RSM_CHECK_FIELD(cfg->recover_ratio >= 0.0f && cfg->recover_ratio <= 1.0f, "recover_ratio");
        RSM_CHECK_FIELD(cfg->recover_m >= 0.0f && cfg->recover_m <= 50.0f * cfg->tmap.cell_m, "recover_m");
        RSM_CHECK_FIELD(cfg->recover_rad >= 0.0f && cfg->recover_rad <= 1.0f &&
                            (cfg->recover_rad == 0.0f || cfg->recover_rad <= 64.0f * cfg->mapmatch.search_step_rad),
                        "recover_rad");
        RSM_CHECK_FIELD(cfg->refuse_poor <= 1u, "refuse_poor");
        RSM_CHECK_FIELD(cfg->map_frozen <= 1u, "map_frozen");
        RSM_CHECK_FIELD(cfg->map_loaded_hit <= RSM_TMAP_MAX_VALUE, "map_loaded_hit");
        RSM_CHECK_FIELD(cfg->global_min_share >= 0.0f && cfg->global_min_share <= 1.0f, "global_min_share");
        RSM_CHECK_FIELD(cfg->global_min_fit >= 0.0f && cfg->global_min_fit <= 1.0f, "global_min_fit");
        RSM_CHECK_FIELD(cfg->global_crowded_fit >= 0.0f && cfg->global_crowded_fit <= 1.0f, "global_crowded_fit");
        RSM_CHECK_FIELD(cfg->global_when_lost <= 1u, "global_when_lost");
        RSM_CHECK_FIELD(cfg->recover_margin >= 0.0f && cfg->recover_margin <= 10.0f, "recover_margin");
        RSM_CHECK_FIELD(cfg->refute_margin >= 0.0f && cfg->refute_margin <= 10.0f, "refute_margin");
        RSM_CHECK_FIELD(cfg->conflict_max >= 0.0f && cfg->conflict_max <= 1.0f, "conflict_max");
        RSM_CHECK_FIELD(cfg->track_min_fit >= 0.0f && cfg->track_min_fit <= 10.0f, "track_min_fit");
        RSM_CHECK_FIELD(cfg->doubt_m > 0.0f && cfg->doubt_m <= 100.0f, "doubt_m");
        RSM_CHECK_FIELD(cfg->doubt_rad > 0.0f && cfg->doubt_rad <= RSM_TWO_PI, "doubt_rad");
        RSM_CHECK_FIELD(cfg->wall_sigma_rad >= 0.0f && cfg->wall_sigma_rad <= 1.0f, "wall_sigma_rad");
        RSM_CHECK_FIELD(cfg->wall_window_rad > 0.0f && cfg->wall_window_rad <= 0.25f * RSM_PI, "wall_window_rad");
        RSM_CHECK_FIELD(cfg->occlusion.window <= RSM_OCCLUSION_MAX_WINDOW, "occlusion.window");
        if (cfg->occlusion.window > 0u) {
            RSM_CHECK_FIELD(cfg->occlusion.span_m > 0.0f && cfg->occlusion.span_m < 100.0f, "occlusion.span_m");
            RSM_CHECK_FIELD(cfg->occlusion.tol_m >= 0.0f && cfg->occlusion.tol_m < 100.0f, "occlusion.tol_m");
            RSM_CHECK_FIELD(cfg->occlusion.slope >= 0.0f && cfg->occlusion.slope < 1000.0f, "occlusion.slope");
            RSM_CHECK_FIELD(cfg->occlusion.margin_m >= 0.0f && cfg->occlusion.margin_m < 100.0f, "occlusion.margin_m");
            RSM_CHECK_FIELD(cfg->occlusion.margin_rel >= 0.0f && cfg->occlusion.margin_rel < 1.0f,
                            "occlusion.margin_rel");
        }
        return rsm_odometry_cal_config_check(&cfg->odometry_cal, field);
    default:
        return RSM_OK;
    }
}

int rsm_localizer_config_check(const rsm_localizer_config_t *cfg, const char **field)
{
    int rc;
    RSM_CHECK_FIELD(cfg != NULL, "cfg");
    RSM_CHECK_FIELD(cfg->method <= RSM_METHOD_MAP, "method");
    RSM_CHECK_FIELD(cfg->limits.max_range_m > cfg->limits.min_range_m, "limits.max_range_m");
    RSM_CHECK_FIELD(cfg->grid.cell_m > 0.0f, "grid.cell_m");
    RSM_CHECK_FIELD(cfg->grid.sigma_m >= 0.0f && cfg->grid.sigma_m * 2.0f < cfg->grid.cell_m, "grid.sigma_m");
    RSM_CHECK_FIELD(cfg->map_min_hits >= 1u, "map_min_hits");
    RSM_CHECK_FIELD(cfg->min_points >= 2u && cfg->min_points <= RSM_MAX_BEAMS, "min_points");
    RSM_CHECK_FIELD(cfg->lost_scans >= 1u, "lost_scans");
    RSM_CHECK_FIELD(cfg->min_keypoints >= 2u && cfg->min_keypoints <= RSM_MAX_KEYPOINTS, "min_keypoints");
    RSM_CHECK_FIELD(cfg->match_window_m >= 0.0f, "match_window_m");
    RSM_CHECK_FIELD(cfg->search_min_m > 0.0f, "search_min_m");
    RSM_CHECK_FIELD(cfg->search_max_m >= cfg->search_min_m, "search_max_m");
    RSM_CHECK_FIELD(cfg->gate_d2 >= 0.0f, "gate_d2");
    RSM_CHECK_FIELD(cfg->r_min_xy_m > 0.0f, "r_min_xy_m");
    RSM_CHECK_FIELD(cfg->r_min_theta_rad > 0.0f, "r_min_theta_rad");
    RSM_CHECK_FIELD(cfg->noise <= RSM_NOISE_FIXED, "noise");
    RSM_CHECK_FIELD(cfg->refine_saturation >= 1u, "refine_saturation");
    RSM_CHECK_FIELD(cfg->refine_noise_scale > 0.0f, "refine_noise_scale");
    RSM_CHECK_FIELD(cfg->cov_floor_m >= 0.0f && cfg->cov_floor_m <= 1.0e3f, "cov_floor_m");
    RSM_CHECK_FIELD(cfg->cov_floor_rad >= 0.0f && cfg->cov_floor_rad <= RSM_PI, "cov_floor_rad");
    /* The Harris part has no init of its own: a bad one would make every
     * detection fail with RSM_ERR_INVAL, read as no key points. */
    RSM_CHECK_FIELD(cfg->harris.k_den > 0, "harris.k_den");
    RSM_CHECK_FIELD(cfg->harris.k_num >= 0, "harris.k_num");
    RSM_CHECK_FIELD(cfg->harris.nms_radius >= 0, "harris.nms_radius");
    RSM_CHECK_FIELD(fabsf(cfg->laser_mount.x) < 100.0f, "laser_mount.x");
    RSM_CHECK_FIELD(fabsf(cfg->laser_mount.y) < 100.0f, "laser_mount.y");
    RSM_CHECK_FIELD(fabsf(cfg->laser_mount.theta) <= RSM_TWO_PI, "laser_mount.theta");
    RSM_CHECK_FIELD(cfg->laser_upside_down <= 1u, "laser_upside_down");
    if ((rc = rsm_odometry_config_check(&cfg->odometry, field)) != RSM_OK) {
        return rc;
    }
    return check_method_part(cfg, field);
}
