/* What every fuzz target does when an invariant fails: stop the run where it
 * happened, so that libFuzzer keeps the input. */
#ifndef RSM_FUZZ_CHECK_H
#define RSM_FUZZ_CHECK_H

#include <stddef.h>
#include <stdint.h>

#define CHECK(cond)            \
    do {                       \
        if (!(cond)) {         \
            __builtin_trap();  \
        }                      \
    } while (0)

/* Size of the next chunk of a chunked feed: 1..max bytes from the
 * xorshift state *rng, never more than the remaining bytes. */
static inline size_t fuzz_next_chunk(uint32_t *rng, size_t remaining, size_t max)
{
    size_t chunk;
    *rng ^= *rng << 13;
    *rng ^= *rng >> 17;
    *rng ^= *rng << 5;
    chunk = (size_t)(*rng % max) + 1u;
    return chunk < remaining ? chunk : remaining;
}

#endif
