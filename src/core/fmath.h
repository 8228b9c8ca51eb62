/* The core's own single-precision elementary functions (internal, not
 * installed).
 *
 * Why: libm's sinf/cosf/atan2f/logf are not correctly rounded, and
 * different C libraries round differently in the last bit (newlib's and
 * glibc's sinf/cosf disagree on some beam angles). One ulp is enough to flip
 * a gate decision some scans later, so a capture replayed on a host would not
 * reproduce what the robot did. These functions use only IEEE float
 * additions, multiplications, divisions and conversions, in a fixed order,
 * so they give the same bits on every IEEE-754 machine that evaluates float
 * expressions in float (FLT_EVAL_METHOD 0: x86-64 SSE, Cortex-M4F, ...) and
 * compiles without contracting a*b+c into a fused multiply-add
 * (-ffp-contract=off, which the build sets).
 *
 * Functions that IEEE defines exactly (sqrtf, fabsf, fmaxf, fmodf, floorf,
 * isfinite) give the same bits in every correct libm and stay libm's;
 * rsm_floorf/rsm_ceilf are here only because the core calls them in loops
 * and Cortex-M4F has no rounding instruction (they are exact too).
 *
 * Accuracy against libm in double, as tests/unit/test_fmath.c checks it
 * (measured maxima in brackets): rsm_sinf and rsm_cosf within 6e-8 absolute
 * for |x| <= 8192 [5.1e-8] and within 1 ulp of the result for |x| <= 7
 * [0.85; 3.4 % of results are not the correctly rounded one, glibc's 1.3 %];
 * rsm_atan2f within 3 ulp [2.92] and 3e-7 absolute [2.7e-7]; rsm_logf
 * within 2 ulp [1.75]. (The default method uses sine and cosine only;
 * atan2 and log serve the paper's method and ICP.)
 * Reentrant, no state, no errno. */
#ifndef RSM_FMATH_H
#define RSM_FMATH_H

#include <math.h>
#include <stdint.h>

/* sin(x) and cos(x), x in radians. Non-finite x gives NaN. The argument is
 * reduced exactly for |x| < 25000; beyond, the result is still deterministic
 * but loses accuracy (the core only passes angles of a few turns). */
float rsm_sinf(float x);
float rsm_cosf(float x);

/* *s = rsm_sinf(x) and *c = rsm_cosf(x), the same bits, for one argument
 * reduction: most callers want both. */
void rsm_sincosf(float x, float *s, float *c);

/* The angle of (x, y) in [-pi, pi], with C99's atan2 rules for zeros and
 * infinities; NaN if either is NaN. */
float rsm_atan2f(float y, float x);

/* Natural logarithm: -inf at 0, NaN below 0 or for NaN, +inf at +inf. */
float rsm_logf(float x);

/* Largest integer <= x and smallest integer >= x, exactly (signed zeros and
 * non-finite values as C99's floorf/ceilf). Inline: the map's writes take
 * a floor per beam and per return, and a call was a fifth of that. */
static inline float rsm_floorf(float x)
{
    float t;
    if (!(fabsf(x) < 0x1p+23f)) {
        return x; /* already an integer, or not finite */
    }
    t = (float)(int32_t)x; /* truncation toward zero, exact here */
    if (t > x) {
        t -= 1.0f;
    }
    /* x * 0 keeps floorf(-0.0) == -0.0; any other x gives t != 0 or +0. */
    return t == 0.0f ? x * 0.0f : t;
}

static inline float rsm_ceilf(float x)
{
    float t;
    if (!(fabsf(x) < 0x1p+23f)) {
        return x;
    }
    t = (float)(int32_t)x;
    if (t < x) {
        t += 1.0f;
    }
    /* ceilf(-0.3) is -0.0, as x * 0 gives. */
    return t == 0.0f ? x * 0.0f : t;
}

#endif /* RSM_FMATH_H */
