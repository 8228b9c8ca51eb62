#include "rsm/hal.h"

#include <limits.h>

#include "rsm/status.h"

/* Callbacks return int, so one call never asks for more than INT_MAX bytes:
 * a larger count could not be reported back. */
static size_t clamp_to_int(size_t n)
{
    return n > (size_t)INT_MAX ? (size_t)INT_MAX : n;
}

int rsm_link_read(const rsm_link_t *link, uint8_t *buf, size_t cap, uint32_t timeout_us)
{
    int n;
    if (link == NULL || (buf == NULL && cap > 0u)) {
        return RSM_ERR_INVAL;
    }
    if (link->read == NULL) {
        return RSM_ERR_NOSYS;
    }
    cap = clamp_to_int(cap);
    n = link->read(link->ctx, buf, cap, timeout_us);
    /* A port that claims more than it was given has written past buf: say so
     * rather than let a codec read the garbage. */
    if (n > 0 && (size_t)n > cap) {
        return RSM_ERR_IO;
    }
    return n;
}

int rsm_link_write_all(const rsm_link_t *link, const uint8_t *buf, size_t len, size_t *written)
{
    size_t done = 0;
    int status = RSM_OK;
    if (written != NULL) {
        *written = 0;
    }
    if (link == NULL || (buf == NULL && len > 0u)) {
        return RSM_ERR_INVAL;
    }
    if (link->write == NULL) {
        return RSM_ERR_NOSYS;
    }
    while (done < len) {
        const size_t chunk = clamp_to_int(len - done);
        const int n = link->write(link->ctx, buf + done, chunk);
        if (n < 0) {
            status = n;
            break;
        }
        if (n == 0) {
            /* The port already waited its own transmit timeout; retrying here
             * could spin forever on a dead line. */
            status = RSM_ERR_TIMEOUT;
            break;
        }
        if ((size_t)n > chunk) {
            status = RSM_ERR_IO;
            break;
        }
        done += (size_t)n;
    }
    if (written != NULL) {
        *written = done;
    }
    return status;
}

int rsm_link_set_baud(const rsm_link_t *link, uint32_t baud)
{
    if (link == NULL || baud == 0u) {
        return RSM_ERR_INVAL;
    }
    if (link->set_baud == NULL) {
        return RSM_ERR_NOSYS;
    }
    return link->set_baud(link->ctx, baud);
}

int rsm_link_flush(const rsm_link_t *link)
{
    if (link == NULL) {
        return RSM_ERR_INVAL;
    }
    if (link->flush == NULL) {
        return RSM_ERR_NOSYS;
    }
    return link->flush(link->ctx);
}

int rsm_clock_now_us(const rsm_clock_t *clock, uint64_t *now_us)
{
    if (clock == NULL || now_us == NULL) {
        return RSM_ERR_INVAL;
    }
    if (clock->now_us == NULL) {
        return RSM_ERR_NOSYS;
    }
    *now_us = clock->now_us(clock->ctx);
    return RSM_OK;
}
