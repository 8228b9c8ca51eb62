/* The walls' direction modulo a quarter turn (wallgrid.h). Directions are
 * added as unit vectors at four times their angle, so that the four
 * directions of one grid add up instead of cancelling, and with weights of
 * their length: a long wall outweighs a chair's legs. */
#include "localizer/wallgrid.h"

#include <math.h>

#include "core/fmath.h"

/* A straight stretch: its ends this far apart at least (closer, range noise
 * turns it anywhere) and at most (farther, it spans a gap or a corner) ... */
#define WALL_MIN_M 0.03f
#define WALL_MAX_M 0.3f
/* ... and its middle point within this share of its length off the line
 * between them (1 cm at 0.3 m). */
#define WALL_STRAIGHT 0.033f

#define QUARTER (0.5f * RSM_PI)

float rsm_wallgrid_diff(float a, float b)
{
    float d = fmodf(a - b + 0.5f * QUARTER, QUARTER);
    if (d < 0.0f) {
        d += QUARTER;
    }
    return d - 0.5f * QUARTER;
}

void rsm_wallgrid_direction(const rsm_point_t *pts, size_t n, float expect, float window_rad, float *dir,
                            float *support, float *straight)
{
    /* The expected direction at four times its angle, and the cosine of
     * four times the window: a stretch passes when its quadrupled angle
     * lies within that of the expected one. */
    const float ec = rsm_cosf(4.0f * expect);
    const float es = rsm_sinf(4.0f * expect);
    const float min_cos = window_rad >= 0.25f * RSM_PI ? -2.0f : rsm_cosf(4.0f * window_rad);
    float c_sum = 0.0f;
    float s_sum = 0.0f;
    float length = 0.0f;
    float all = 0.0f;
    size_t i;
    for (i = 0; i + 2u < n; ++i) {
        const float dx = pts[i + 2u].x - pts[i].x;
        const float dy = pts[i + 2u].y - pts[i].y;
        const float d2 = dx * dx + dy * dy;
        float off;
        float d;
        float c2;
        float s2;
        float c4;
        float s4;
        float rc;
        float rs;
        if (!(d2 >= WALL_MIN_M * WALL_MIN_M && d2 <= WALL_MAX_M * WALL_MAX_M)) {
            continue;
        }
        off = (pts[i + 1u].x - pts[i].x) * dy - (pts[i + 1u].y - pts[i].y) * dx; /* length times distance */
        if (off * off > WALL_STRAIGHT * WALL_STRAIGHT * d2 * d2) {
            continue;
        }
        /* cos and sin of twice, then four times, the angle, from the
         * squared components: no trigonometry per stretch. */
        c2 = (dx * dx - dy * dy) / d2;
        s2 = 2.0f * dx * dy / d2;
        c4 = c2 * c2 - s2 * s2;
        s4 = 2.0f * c2 * s2;
        rc = c4 * ec + s4 * es; /* relative to the expected direction */
        rs = s4 * ec - c4 * es;
        d = sqrtf(d2);
        all += d;
        if (rc < min_cos) {
            continue;
        }
        c_sum += d * rc;
        s_sum += d * rs;
        length += d;
    }
    *support = length;
    *straight = all;
    *dir = length > 0.0f ? expect + 0.25f * rsm_atan2f(s_sum, c_sum) : expect;
}
