#include "test_support.h"

#include <stdio.h>

const char *rsm_test_source_path(char *out, size_t cap, const char *rel)
{
    int n = snprintf(out, cap, "%s/%s", RSM_SOURCE_DIR, rel);
    if (n < 0 || (size_t)n >= cap) {
        return NULL;
    }
    return out;
}

uint32_t rsm_test_rng_next(uint32_t *state)
{
    uint32_t x = *state;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    *state = x;
    return x;
}

float rsm_test_rng_uniform(uint32_t *state, float lo, float hi)
{
    const float u = (float)(rsm_test_rng_next(state) >> 8) / 16777216.0f;
    return lo + (hi - lo) * u;
}
