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

static void heap_add(size_t n)
{
    heap_now += n;
    if (heap_now > heap_max) {
        heap_max = heap_now;
    }
}

void *nav_malloc(size_t n)
{
    heap_head_t *h;
    if (n > SIZE_MAX - sizeof *h) {
        return NULL;
    }
    h = (heap_head_t *)malloc(sizeof *h + n);
    if (h == NULL) {
        return NULL;
    }
    h->size = n;
    heap_add(n);
    return h + 1;
}

void *nav_calloc(size_t count, size_t size)
{
    heap_head_t *h;
    size_t n;
    if (size != 0u && count > SIZE_MAX / size) {
        return NULL;
    }
    n = count * size;
    if (n > SIZE_MAX - sizeof *h) {
        return NULL;
    }
    /* calloc, not malloc and a memset: a large block's pages stay
     * untouched (and not resident) until used, as the tile store's are. */
    h = (heap_head_t *)calloc(1u, sizeof *h + n);
    if (h == NULL) {
        return NULL;
    }
    h->size = n;
    heap_add(n);
    return h + 1;
}

void *nav_realloc(void *p, size_t n)
{
    heap_head_t *h;
    size_t old;
    if (p == NULL) {
        return nav_malloc(n);
    }
    if (n > SIZE_MAX - sizeof *h) {
        return NULL;
    }
    h = (heap_head_t *)p - 1;
    old = h->size;
    h = (heap_head_t *)realloc(h, sizeof *h + n);
    if (h == NULL) {
        return NULL; /* the old block stays, as realloc leaves it */
    }
    h->size = n;
    heap_now -= old;
    heap_add(n);
    return h + 1;
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

size_t nav_heap_bytes(void)
{
    return heap_now;
}

size_t nav_heap_peak(void)
{
    return heap_max;
}
