#include "heap.h"

#include <stdint.h>
#include <stdlib.h>

/* Each block carries its size in front, so that nav_free knows what it
 * gives back; the prefix is as large as the most aligned of these types,
 * so that on the hosts this tool is built for (x86-64, aarch64: 16 bytes)
 * the block keeps malloc's alignment. */
typedef union heap_head {
    size_t size;
    long double ld;
    void *p;
    long long ll;
} heap_head_t;

/* One count for the process, as the allocator it stands in front of: the
 * program is single-threaded, and its parts (capture reader, map picture,
 * ROS map import) allocate without a handle to pass it through. */
static size_t heap_now;
static size_t heap_max;

/* Whether a block of n bytes and its header fit in a size_t. */
static int heap_fits(size_t n)
{
    return n <= SIZE_MAX - sizeof(heap_head_t);
}

/* A block from the allocator (or NULL) stamped with its size n and
 * counted: what the caller gets. */
static void *heap_took(heap_head_t *h, size_t n)
{
    if (h == NULL) {
        return NULL;
    }
    h->size = n;
    heap_now += n;
    if (heap_now > heap_max) {
        heap_max = heap_now;
    }
    return h + 1;
}

void *nav_malloc(size_t n)
{
    return heap_fits(n) ? heap_took((heap_head_t *)malloc(sizeof(heap_head_t) + n), n) : NULL;
}

void *nav_calloc(size_t count, size_t size)
{
    const size_t n = count * size;
    if ((size != 0u && count > SIZE_MAX / size) || !heap_fits(n)) {
        return NULL;
    }
    /* calloc, not malloc and a memset: a large block's pages stay
     * untouched (and not resident) until used, as the tile store's are. */
    return heap_took((heap_head_t *)calloc(1u, sizeof(heap_head_t) + n), n);
}

void *nav_realloc(void *p, size_t n)
{
    heap_head_t *h;
    void *q;
    size_t old;
    if (p == NULL) {
        return nav_malloc(n);
    }
    if (!heap_fits(n)) {
        return NULL;
    }
    h = (heap_head_t *)p - 1;
    old = h->size;
    heap_now -= old;
    q = heap_took((heap_head_t *)realloc(h, sizeof *h + n), n);
    if (q == NULL) {
        heap_now += old; /* the old block stays, as realloc leaves it */
    }
    return q;
}

void nav_free(void *p)
{
    heap_head_t *h;
    if (p == NULL) {
        return;
    }
    h = (heap_head_t *)p - 1;
    heap_now -= h->size;
    free(h);
}

size_t nav_heap_peak(void)
{
    return heap_max;
}
