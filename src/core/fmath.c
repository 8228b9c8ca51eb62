/* Deterministic float elementary functions; see fmath.h for why. Written from
 * the series: Taylor polynomials on a reduced range, where the truncation
 * error is far below one float ulp, evaluated by Horner's rule. */
#include "core/fmath.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

/* The same bits everywhere need float arithmetic done in float. */
#if !defined(FLT_EVAL_METHOD) || FLT_EVAL_METHOD != 0
#error "rsm needs FLT_EVAL_METHOD == 0 (float expressions evaluated in float, e.g. SSE or a single-precision FPU)"
#endif

/* pi/2 = PIO2_1 + PIO2_2 + PIO2_3 (Cody and Waite's reduction). PIO2_1 has 8
 * significant bits and PIO2_2 10, so k * PIO2_1 and k * PIO2_2 are exact for
 * |k| < 2^14, and x - k * PIO2_1 is exact near a multiple of pi/2. */
#define PIO2_1 0x1.92p+0f
#define PIO2_2 0x1.fb4p-12f
#define PIO2_3 0x1.4442d2p-24f
#define TWO_OVER_PI 0x1.45f306p-1f
#define REDUCE_LIMIT 25000.0f /* |k| stays below 2^14 */

#define PI_F 0x1.921fb6p+1f
#define PIO2_F 0x1.921fb6p+0f
#define PIO4_F 0x1.921fb6p-1f
#define TAN_PIO8 0x1.a827dap-2f /* sqrt(2) - 1 */

/* ln 2 = LN2_HI + LN2_LO; LN2_HI has 16 significant bits, so e * LN2_HI is
 * exact for every float exponent e. */
#define LN2_HI 0x1.62e4p-1f
#define LN2_LO 0x1.7f7d1cp-20f
#define SQRT2 0x1.6a09e6p+0f

/* sin and cos of r + rlo for |r| <= pi/4 + a little, rlo the reduction's
 * low part (|rlo| < ulp(r)): sin(r + rlo) = sin r + rlo cos r, cos(r + rlo)
 * = cos r - rlo sin r to far below an ulp. Taylor to r^9 and r^10: the next
 * terms are below 2e-9 and 1.2e-10 there, under 1/30 ulp of 1. */
static float sin_poly(float r, float rlo)
{
    const float z = r * r;
    return r + (rlo + r * z * (-1.0f / 6.0f + z * (1.0f / 120.0f + z * (-1.0f / 5040.0f + z * (1.0f / 362880.0f)))));
}

static float cos_poly(float r, float rlo)
{
    const float z = r * r;
    const float hz = 0.5f * z;
    const float w = 1.0f - hz;
    /* 1 - w is exact (w is in [0.69, 1]), so (1 - w) - hz is the rounding
     * error of w, added back with the small terms. */
    return w + (((1.0f - w) - hz) +
                (z * z * (1.0f / 24.0f + z * (-1.0f / 720.0f + z * (1.0f / 40320.0f + z * (-1.0f / 3628800.0f)))) -
                 r * rlo));
}

/* x = k pi/2 + *r + *rlo with |*r| <= pi/4 (about) and *rlo the part of the
 * reduced argument below *r's last bit; returns k mod 4. */
static uint32_t reduce(float x, float *r, float *rlo)
{
    float kf;
    float a;
    float c;
    float s;
    float lo;
    int32_t k;
    if (!(fabsf(x) < REDUCE_LIMIT)) {
        /* Exact (fmodf is), so still deterministic; the core never gets here. */
        x = fmodf(x, 4.0f * PIO2_F);
    }
    kf = x * TWO_OVER_PI;
    k = (int32_t)(kf >= 0.0f ? kf + 0.5f : kf - 0.5f);
    kf = (float)k;
    a = x - kf * PIO2_1; /* exact */
    c = -(kf * PIO2_2);  /* exact */
    /* s + error = a + c exactly (Knuth's two-sum). */
    s = a + c;
    {
        const float a2 = s - c;
        const float c2 = s - a2;
        lo = (a - a2) + (c - c2);
    }
    lo -= kf * PIO2_3;
    *r = s + lo;
    *rlo = lo - (*r - s);
    return (uint32_t)k & 3u;
}

float rsm_sinf(float x)
{
    float r;
    float rlo;
    uint32_t q;
    if (!isfinite(x)) {
        return x - x; /* NaN for inf and NaN */
    }
    if (fabsf(x) < 0x1p-12f) {
        return x; /* x^3 / 6 is below half an ulp of x; keeps the sign of -0 */
    }
    q = reduce(x, &r, &rlo);
    switch (q) {
    case 0u:
        return sin_poly(r, rlo);
    case 1u:
        return cos_poly(r, rlo);
    case 2u:
        return -sin_poly(r, rlo);
    default:
        return -cos_poly(r, rlo);
    }
}

float rsm_cosf(float x)
{
    float r;
    float rlo;
    uint32_t q;
    if (!isfinite(x)) {
        return x - x;
    }
    q = reduce(x, &r, &rlo);
    switch (q) {
    case 0u:
        return cos_poly(r, rlo);
    case 1u:
        return -sin_poly(r, rlo);
    case 2u:
        return -cos_poly(r, rlo);
    default:
        return sin_poly(r, rlo);
    }
}

void rsm_sincosf(float x, float *s, float *c)
{
    float r;
    float rlo;
    float sp;
    float cp;
    uint32_t q;
    if (!isfinite(x)) {
        *s = x - x;
        *c = x - x;
        return;
    }
    q = reduce(x, &r, &rlo);
    sp = sin_poly(r, rlo);
    cp = cos_poly(r, rlo);
    switch (q) {
    case 0u:
        *s = sp;
        *c = cp;
        break;
    case 1u:
        *s = cp;
        *c = -sp;
        break;
    case 2u:
        *s = -sp;
        *c = -cp;
        break;
    default:
        *s = -cp;
        *c = sp;
        break;
    }
    if (fabsf(x) < 0x1p-12f) {
        *s = x; /* as rsm_sinf */
    }
}

/* atan t for 0 <= t <= 1: atan t = pi/4 + atan((t - 1) / (t + 1)) moves t
 * above tan(pi/8) to |u| <= tan(pi/8), where the series to u^19 leaves an
 * error below u^21 / 21 < 5e-10. */
static float atan01(float t)
{
    float base = 0.0f;
    float u = t;
    float z;
    if (t > TAN_PIO8) {
        u = (t - 1.0f) / (t + 1.0f);
        base = PIO4_F;
    }
    z = u * u;
    return base +
           (u + u * z * (-1.0f / 3.0f +
                         z * (1.0f / 5.0f +
                              z * (-1.0f / 7.0f +
                                   z * (1.0f / 9.0f +
                                        z * (-1.0f / 11.0f +
                                             z * (1.0f / 13.0f +
                                                  z * (-1.0f / 15.0f + z * (1.0f / 17.0f + z * (-1.0f / 19.0f))))))))));
}

float rsm_atan2f(float y, float x)
{
    const float ax = fabsf(x);
    const float ay = fabsf(y);
    const int swap = ay > ax;
    const float num = swap ? ax : ay;
    const float den = swap ? ay : ax;
    float t;
    float a;
    if (isnan(x) || isnan(y)) {
        return x + y;
    }
    if (den == 0.0f) {
        t = 0.0f; /* both zero */
    } else if (isinf(den)) {
        t = isinf(num) ? 1.0f : 0.0f;
    } else {
        t = num / den;
    }
    a = atan01(t);
    if (swap) {
        a = PIO2_F - a;
    }
    if (signbit(x)) {
        a = PI_F - a;
    }
    return signbit(y) ? -a : a;
}

float rsm_logf(float x)
{
    uint32_t bits;
    int32_t e;
    float m;
    float s;
    float z;
    float lm;
    if (isnan(x) || x < 0.0f) {
        return (x - x) / (x - x); /* NaN */
    }
    if (x == 0.0f) {
        return -1.0f / (x * x); /* -inf */
    }
    if (isinf(x)) {
        return x;
    }
    e = 0;
    if (x < FLT_MIN) {
        x *= 0x1p+25f; /* subnormal: make it normal first */
        e = -25;
    }
    memcpy(&bits, &x, sizeof bits);
    e += (int32_t)((bits >> 23) & 0xFFu) - 127;
    bits = (bits & 0x7FFFFFu) | 0x3F800000u; /* the mantissa, in [1, 2) */
    memcpy(&m, &bits, sizeof m);
    if (m > SQRT2) {
        m *= 0.5f;
        e += 1;
    }
    /* log m = 2 atanh s with s = (m - 1) / (m + 1), |s| <= 0.172: the series
     * to s^9 leaves below 2 s^11 / 11 < 5e-10. */
    s = (m - 1.0f) / (m + 1.0f);
    z = s * s;
    lm = 2.0f * s + 2.0f * s * z * (1.0f / 3.0f + z * (1.0f / 5.0f + z * (1.0f / 7.0f + z * (1.0f / 9.0f))));
    return (float)e * LN2_HI + (lm + (float)e * LN2_LO);
}
