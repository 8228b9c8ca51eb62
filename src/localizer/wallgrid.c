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
    /* floor, not fmodf: one division and a rounding on any target. */
    const float d = a - b;
    return d - QUARTER * rsm_floorf(d / QUARTER + 0.5f);
}

void rsm_wallgrid_direction(const rsm_point_t *pts, size_t n, float expect, float window_rad, float *dir,
                            float *support, float *straight)
{
    /* Each stretch is turned by -expect and its angle quadrupled there
     * (complex squaring twice: no trigonometry, no division), so that the
     * window is a bound on the quadrupled angle's cosine; the factor of
     * its length's fourth power is divided out only for the stretches
     * that count. */
    const float ce = rsm_cosf(expect);
    const float se = rsm_sinf(expect);
    const float min_cos = window_rad >= 0.25f * RSM_PI ? -2.0f : rsm_cosf(4.0f * window_rad);
    float c_sum = 0.0f;
    float s_sum = 0.0f;
    float length = 0.0f;
    float all = 0.0f;
    float ax;
    float ay;
    size_t i;
    if (n < 3u) {
        *support = 0.0f;
        *straight = 0.0f;
        *dir = expect;
        return;
    }
    ax = pts[1].x - pts[0].x;
    ay = pts[1].y - pts[0].y;
    for (i = 2; i < n; ++i) {
        /* The stretch from point i-2 to i, in two steps a and b. */
        const float bx = pts[i].x - pts[i - 1u].x;
        const float by = pts[i].y - pts[i - 1u].y;
        const float dx = ax + bx;
        const float dy = ay + by;
        const float d2 = dx * dx + dy * dy;
        const float off = ax * by - ay * bx; /* its length times the middle point's distance off it */
        ax = bx;
        ay = by;
        if (d2 >= WALL_MIN_M * WALL_MIN_M && d2 <= WALL_MAX_M * WALL_MAX_M &&
            off * off <= WALL_STRAIGHT * WALL_STRAIGHT * d2 * d2) {
            const float xr = dx * ce + dy * se;
            const float yr = dy * ce - dx * se;
            const float c2 = xr * xr - yr * yr;
            const float s2 = 2.0f * xr * yr;
            const float c4 = c2 * c2 - s2 * s2; /* d2^2 cos(4 (angle - expect)) */
            const float d = sqrtf(d2);
            all += d;
            if (c4 >= min_cos * d2 * d2) {
                const float w = d / (d2 * d2);
                c_sum += w * c4;
                s_sum += w * (2.0f * c2 * s2);
                length += d;
            }
        }
    }
    *support = length;
    *straight = all;
    *dir = length > 0.0f ? expect + 0.25f * rsm_atan2f(s_sum, c_sum) : expect;
}
