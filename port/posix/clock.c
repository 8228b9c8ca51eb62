/* rsm_clock_t from the monotonic clock. */
#include "rsm_posix.h"

#include <time.h>

uint64_t rsm_posix_clock_now_us(void *ctx)
{
    struct timespec ts;
    (void)ctx;
    if (clock_gettime(CLOCK_MONOTONIC, &ts) != 0) {
        return 0u;
    }
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

int rsm_posix_clock_init(rsm_clock_t *clock)
{
    if (clock == NULL) {
        return RSM_ERR_INVAL;
    }
    clock->now_us = rsm_posix_clock_now_us;
    clock->ctx = NULL;
    return RSM_OK;
}
