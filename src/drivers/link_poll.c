/* The poll cycle shared by the link drivers (include/rsm/link_poll.h). */
#include "rsm/link_poll.h"

#include "rsm/status.h"
#include "core/check.h"

int rsm_link_rx_init_checked(rsm_link_rx_t *rx, size_t rx_size, unsigned long fingerprint, const rsm_link_t *link,
                             const rsm_clock_t *clock, uint32_t read_timeout_us, uint32_t byte_timeout_us)
{
    if (!RSM_SAME_BUILD(rsm_link_rx_t, rx_size, fingerprint)) {
        return RSM_ERR_CONFIG;
    }
    if (rx == NULL || link == NULL || clock == NULL || link->read == NULL ||
        link->write == NULL || clock->now_us == NULL) {
        return RSM_ERR_INVAL;
    }
    rx->link = link;
    rx->clock = clock;
    rx->read_timeout_us = read_timeout_us;
    rx->byte_timeout_us = byte_timeout_us;
    rx->off = 0u;
    rx->len = 0u;
    rx->stamp_us = 0u;
    rx->last_rx_us = 0u;
    rx->bytes = 0u;
    return RSM_OK;
}

void rsm_link_rx_drop(rsm_link_rx_t *rx)
{
    if (rx == NULL) {
        return;
    }
    (void)rsm_link_flush(rx->link);
    rx->off = 0u;
    rx->len = 0u;
}

uint64_t rsm_link_rx_now(const rsm_link_rx_t *rx)
{
    uint64_t t = 0u;
    if (rx != NULL) {
        (void)rsm_clock_now_us(rx->clock, &t);
    }
    return t;
}

uint64_t rsm_link_next_deadline(const rsm_link_rx_t *rx, const rsm_link_poll_ops_t *ops, const void *drv)
{
    uint64_t now;
    uint64_t wait;
    if (rx == NULL || ops == NULL || ops->until_due == NULL) {
        return UINT64_MAX;
    }
    now = rsm_link_rx_now(rx);
    if (rx->off < rx->len) {
        return now;
    }
    wait = ops->until_due(drv, now);
    return wait > UINT64_MAX - now ? UINT64_MAX : now + wait;
}

int rsm_link_poll(rsm_link_rx_t *rx, const rsm_link_poll_ops_t *ops, void *drv)
{
    uint64_t now;
    uint64_t wait;
    uint32_t timeout;
    int n;
    if (rx == NULL || ops == NULL || ops->drain == NULL || ops->timers == NULL ||
        ops->until_due == NULL || ops->silence == NULL) {
        return RSM_ERR_INVAL;
    }
    now = rsm_link_rx_now(rx);
    /* Bytes left over from the previous read come first. */
    if (ops->drain(drv, now) || ops->timers(drv, now)) {
        return RSM_OK;
    }
    wait = ops->until_due(drv, now);
    timeout = rx->read_timeout_us;
    if (wait < (uint64_t)timeout) {
        timeout = (uint32_t)wait;
    }
    n = rsm_link_read(rx->link, rx->buf, sizeof rx->buf, timeout);
    now = rsm_link_rx_now(rx);
    if (n < 0) {
        return n;
    }
    if (n > 0) {
        rx->off = 0u;
        rx->len = (size_t)n;
        rx->stamp_us = now;
        rx->last_rx_us = now;
        rx->bytes += (uint64_t)n;
        if (ops->drain(drv, now)) {
            return RSM_OK;
        }
    } else if (now - rx->last_rx_us >= rx->byte_timeout_us && ops->silence(drv, now)) {
        return RSM_OK;
    }
    (void)ops->timers(drv, now);
    return RSM_OK;
}
