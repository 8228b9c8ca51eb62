/* Included first by the files whose loops are most of a scan's cost (the
 * map matcher, the map writer, the scan's points): GCC compiles them for
 * speed even in a build for size (-Os, what most firmware uses), where they
 * would cost a Cortex-M4F about a fifth more instructions per scan; every
 * other file keeps the build's choice. The float operations are the same
 * at either level (-ffp-contract=off), so the results are too. Not an
 * include guard on purpose: each file that includes it gets the pragma.
 * Internal to the library. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__OPTIMIZE_SIZE__)
#pragma GCC optimize("O2")
#endif
