#include "rsm/scan.h"

#include <math.h>

#include "rsm/status.h"
#include "fmath.h"

rsm_scan_limits_t rsm_scan_limits_default(void)
{
    rsm_scan_limits_t l;
    l.min_range_m = 0.05f;
    l.max_range_m = 20.0f;
    return l;
}

int rsm_scan_set_uniform(rsm_scan_t *scan, size_t count, float start_rad, float step_rad)
{
    size_t i;
    if (scan == NULL) {
        return RSM_ERR_INVAL;
    }
    if (count > RSM_MAX_BEAMS) {
        return RSM_ERR_NOMEM;
    }
    for (i = 0; i < count; ++i) {
        scan->angle_rad[i] = start_rad + step_rad * (float)i;
    }
    scan->count = count;
    return RSM_OK;
}

int rsm_scan_reading_ok(const rsm_scan_t *scan, size_t i, const rsm_scan_limits_t *lim,
                        rsm_scan_drops_t *drops)
{
    float r;
    /* Out-of-range indices and missing arguments are not readings: refused,
     * and not counted as drops. */
    if (scan == NULL || lim == NULL || i >= scan->count || i >= RSM_MAX_BEAMS) {
        return 0;
    }
    r = scan->range_m[i];
    if (!isfinite(r) || !isfinite(scan->angle_rad[i])) {
        if (drops != NULL) {
            drops->nan++;
        }
        return 0;
    }
    if (r <= lim->min_range_m) {
        if (drops != NULL) {
            drops->too_short++;
        }
        return 0;
    }
    if (r >= lim->max_range_m) {
        if (drops != NULL) {
            drops->too_long++;
        }
        return 0;
    }
    return 1;
}

int rsm_scan_to_points(const rsm_scan_t *scan, const rsm_scan_limits_t *lim, rsm_point_t *out,
                       size_t cap, rsm_scan_drops_t *drops)
{
    size_t i;
    size_t n = 0;
    if (scan == NULL || lim == NULL || out == NULL || scan->count > RSM_MAX_BEAMS) {
        return RSM_ERR_INVAL;
    }
    for (i = 0; i < scan->count && n < cap; ++i) {
        if (rsm_scan_reading_ok(scan, i, lim, drops)) {
            out[n].x = scan->range_m[i] * rsm_cosf(scan->angle_rad[i]);
            out[n].y = scan->range_m[i] * rsm_sinf(scan->angle_rad[i]);
            ++n;
        }
    }
    return (int)n;
}
