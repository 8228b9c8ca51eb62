/* rsm-nav's heap, counted: every block the tool's own files allocate goes
 * through these four calls, which keep the bytes it holds now and the most
 * it ever held (zlib's and stdio's blocks are not counted). The summary
 * prints the peak, and the tests compare it between a short and a long
 * run: a count that, unlike resident memory, is the same on every run of a
 * build under any load or sanitizer (issue 30: an array that grew with
 * every scan). The library itself has no heap. */
#ifndef RSM_NAV_HEAP_H
#define RSM_NAV_HEAP_H

#include <stddef.h>

/* As malloc, calloc, realloc and free (NULL when out of memory, or when
 * the request overflows; nav_free(NULL) does nothing). A block from one of
 * them is given back with nav_free or nav_realloc, never with free. */
void *nav_malloc(size_t n);
void *nav_calloc(size_t count, size_t size);
void *nav_realloc(void *p, size_t n);
void nav_free(void *p);

/* The most bytes the program held at once since it started (requested
 * sizes, not the allocator's rounding). */
size_t nav_heap_peak(void);

#endif
