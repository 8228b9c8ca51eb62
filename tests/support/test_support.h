/* Helpers shared by the unit tests: where the project's files are, a generator. */
#ifndef RSM_TEST_SUPPORT_H
#define RSM_TEST_SUPPORT_H

#include <stddef.h>
#include <stdint.h>

/* Writes "<source tree>/<rel>" into out (cap bytes); returns out, or NULL if
 * too long. Tests read only the repository (tests/data). */
const char *rsm_test_source_path(char *out, size_t cap, const char *rel);

/* Small deterministic generator for randomised tests (xorshift32; the
 * caller keeps the non-zero state, so every test is repeatable). */
uint32_t rsm_test_rng_next(uint32_t *state);

/* Uniform in [lo, hi) from rsm_test_rng_next. */
float rsm_test_rng_uniform(uint32_t *state, float lo, float hi);

/* Size of the next piece when a test feeds a stream in chunks: 1..max
 * bytes from the generator, at most remaining; everything (remaining) when
 * *seed is 0. */
size_t rsm_test_chunk(uint32_t *seed, size_t remaining, size_t max);

/* Reads the values of the index-th line (0-based) of the data file
 * <source tree>/<rel> that starts with the word key: whitespace-separated
 * numbers in the given base (16 for hex bytes, 10 for decimals), at most cap
 * of them, into vals. Returns how many were read (0 if the file or the line
 * is missing). */
size_t rsm_test_data_values(const char *rel, const char *key, size_t index, int base,
                            unsigned long *vals, size_t cap);

#endif
