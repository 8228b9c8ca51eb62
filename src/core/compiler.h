/* Compiler-specific hints, each with a plain C99 fallback. Internal to the
 * library. */
#ifndef RSM_COMPILER_H
#define RSM_COMPILER_H

/* Keeps a hot loop out of a large caller, where the compiler would spill
 * its state (GCC and Clang); elsewhere the compiler decides. */
#if defined(__GNUC__) || defined(__clang__)
#define RSM_NOINLINE __attribute__((noinline))
#else
#define RSM_NOINLINE
#endif

/* Makes the compiler copy a function into each caller, so that arguments
 * that are constants there (a loop's direction) fold away; GCC and Clang
 * otherwise keep one copy and test them at run time. */
#if defined(__GNUC__) || defined(__clang__)
#define RSM_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define RSM_ALWAYS_INLINE inline
#endif

/* 1 where every float operation is a call into the compiler's library (an
 * Arm core built with soft float: Cortex-M0+, M3): there a few hot loops
 * take integer shortcuts with the same bits as the float operations. */
#if defined(__arm__) && !defined(__ARM_FP)
#define RSM_SOFT_FLOAT 1
#else
#define RSM_SOFT_FLOAT 0
#endif

/* The index of the highest set bit of x (x > 0): one instruction where the
 * core has it (clz on Armv7-M, bsr on x86). */
static inline unsigned rsm_top_bit(unsigned long x)
{
#if defined(__GNUC__) || defined(__clang__)
    return (unsigned)(sizeof(unsigned long) * 8u - 1u) - (unsigned)__builtin_clzl(x);
#else
    unsigned k = 0;
    while ((x >>= 1) != 0u) {
        ++k;
    }
    return k;
#endif
}

#endif /* RSM_COMPILER_H */
