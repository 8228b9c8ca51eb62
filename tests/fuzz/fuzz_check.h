/* What every fuzz target does when an invariant fails: stop the run where it
 * happened, so that libFuzzer keeps the input. */
#ifndef RSM_FUZZ_CHECK_H
#define RSM_FUZZ_CHECK_H

#define CHECK(cond)            \
    do {                       \
        if (!(cond)) {         \
            __builtin_trap();  \
        }                      \
    } while (0)

#endif
