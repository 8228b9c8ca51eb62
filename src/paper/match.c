#include "paper/match.h"

#include <math.h>

#include "rsm/status.h"

int rsm_match_tentative(const rsm_point_t *ref, size_t nref, const rsm_point_t *cur, size_t ncur,
                        float max_nn_m, float w_m, rsm_match_t *out, size_t cap, size_t *dropped)
{
    size_t r;
    size_t n = 0;
    size_t lost = 0;
    if ((nref > 0 && ref == NULL) || (ncur > 0 && cur == NULL) || (cap > 0 && out == NULL) ||
        nref > 65535u || ncur > 65535u || !(max_nn_m >= 0.0f) || !(w_m >= 0.0f)) {
        return RSM_ERR_INVAL;
    }
    for (r = 0; r < nref; ++r) {
        float best = max_nn_m * max_nn_m;
        size_t nn = ncur;
        size_t c;
        for (c = 0; c < ncur; ++c) {
            const float dx = cur[c].x - ref[r].x;
            const float dy = cur[c].y - ref[r].y;
            const float d2 = dx * dx + dy * dy;
            if (d2 <= best) {
                if (d2 < best || nn == ncur) {
                    best = d2;
                    nn = c;
                }
            }
        }
        if (nn == ncur) {
            continue;
        }
        for (c = 0; c < ncur; ++c) {
            if (fabsf(cur[c].x - cur[nn].x) <= w_m && fabsf(cur[c].y - cur[nn].y) <= w_m) {
                if (n < cap) {
                    out[n].ref = (uint16_t)r;
                    out[n].cur = (uint16_t)c;
                    ++n;
                } else {
                    ++lost;
                }
            }
        }
    }
    if (dropped != NULL) {
        *dropped = lost;
    }
    return (int)n;
}
