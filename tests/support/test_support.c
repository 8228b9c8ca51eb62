#include "test_support.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

size_t rsm_test_data_values(const char *rel, const char *key, size_t index, int base,
                            unsigned long *vals, size_t cap)
{
    char path[1024];
    char line[2048];
    FILE *f;
    size_t seen = 0;
    size_t n = 0;
    const size_t klen = strlen(key);
    if (rsm_test_source_path(path, sizeof path, rel) == NULL || (f = fopen(path, "r")) == NULL) {
        return 0;
    }
    while (fgets(line, sizeof line, f) != NULL) {
        char *p;
        if (strncmp(line, key, klen) != 0 || line[klen] != ' ' || seen++ != index) {
            continue;
        }
        p = line + klen;
        while (n < cap) {
            char *end;
            const unsigned long v = strtoul(p, &end, base);
            if (end == p) {
                break;
            }
            vals[n++] = v;
            p = end;
        }
        break;
    }
    fclose(f);
    return n;
}

size_t rsm_test_chunk(uint32_t *seed, size_t remaining, size_t max)
{
    size_t c;
    if (*seed == 0u) {
        return remaining;
    }
    c = (size_t)(rsm_test_rng_next(seed) % max) + 1u;
    return c < remaining ? c : remaining;
}
