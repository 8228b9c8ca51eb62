#include "uart_ring.h"

#include <limits.h>

#include "rsm/status.h"

#define RING_MASK ((uint32_t)(RSM_UART_RING_SIZE - 1))

/* head and tail only ever grow (modulo 2^32). Because the ring size divides
 * 2^32, head - tail is the fill level even across the wrap, and the slot of
 * count c is c & RING_MASK. Each index has a single writer, so neither side
 * needs a lock: the producer reads tail to see free space, the consumer reads
 * head to see data. */

void rsm_uart_ring_init(rsm_uart_ring_t *ring)
{
    ring->head = 0u;
    ring->tail = 0u;
    ring->overflows = 0u;
}

int rsm_uart_ring_push(rsm_uart_ring_t *ring, uint8_t byte)
{
    const uint32_t head = ring->head;
    if ((uint32_t)(head - ring->tail) >= (uint32_t)RSM_UART_RING_SIZE) {
        ring->overflows = ring->overflows + 1u;
        return 0;
    }
    ring->buf[head & RING_MASK] = byte;
    /* The byte must be in place before the new head makes it visible. */
    RSM_UART_RING_BARRIER();
    ring->head = head + 1u;
    return 1;
}

size_t rsm_uart_ring_push_buf(rsm_uart_ring_t *ring, const uint8_t *data, size_t n)
{
    const uint32_t head = ring->head;
    const uint32_t used = head - ring->tail;
    const size_t space = used >= (uint32_t)RSM_UART_RING_SIZE
                             ? 0u
                             : (size_t)((uint32_t)RSM_UART_RING_SIZE - used);
    const size_t take = n < space ? n : space;
    size_t i;
    for (i = 0; i < take; ++i) {
        ring->buf[(head + (uint32_t)i) & RING_MASK] = data[i];
    }
    if (take < n) {
        /* Count every byte lost; the counter wraps rather than saturates so
         * that the consumer can take differences between two readings. */
        ring->overflows = ring->overflows + (uint32_t)(n - take);
    }
    RSM_UART_RING_BARRIER();
    ring->head = head + (uint32_t)take;
    return take;
}

size_t rsm_uart_ring_pop(rsm_uart_ring_t *ring, uint8_t *out, size_t cap)
{
    const uint32_t tail = ring->tail;
    const uint32_t avail = ring->head - tail; /* read head once: it may move */
    size_t n = avail > (uint32_t)RSM_UART_RING_SIZE ? (size_t)RSM_UART_RING_SIZE : (size_t)avail;
    size_t i;
    if (n > cap) {
        n = cap;
    }
    /* Read the bytes only after seeing the head that published them. */
    RSM_UART_RING_BARRIER();
    for (i = 0; i < n; ++i) {
        out[i] = ring->buf[(tail + (uint32_t)i) & RING_MASK];
    }
    /* And release their slots only after they have been copied out. */
    RSM_UART_RING_BARRIER();
    ring->tail = tail + (uint32_t)n;
    return n;
}

void rsm_uart_ring_clear(rsm_uart_ring_t *ring)
{
    ring->tail = ring->head;
}

size_t rsm_uart_ring_count(const rsm_uart_ring_t *ring)
{
    const uint32_t used = ring->head - ring->tail;
    return used > (uint32_t)RSM_UART_RING_SIZE ? (size_t)RSM_UART_RING_SIZE : (size_t)used;
}

uint32_t rsm_uart_ring_overflows(const rsm_uart_ring_t *ring)
{
    return ring->overflows;
}

/* ---- link glue -------------------------------------------------------------- */

static int uart_link_read(void *ctx, uint8_t *buf, size_t cap, uint32_t timeout_us)
{
    rsm_uart_link_t *uart = (rsm_uart_link_t *)ctx;
    uint64_t start_us = 0u;
    int started = 0;
    if (cap == 0u) {
        return 0;
    }
    for (;;) {
        /* At most RSM_UART_RING_SIZE (<= 2^30) bytes: fits an int. */
        const size_t n = rsm_uart_ring_pop(uart->rx, buf, cap);
        uint64_t now_us;
        if (n > 0u) {
            return (int)n;
        }
        if (timeout_us == 0u) {
            return 0;
        }
        now_us = uart->clock.now_us(uart->clock.ctx);
        if (!started) {
            start_us = now_us;
            started = 1;
        } else if (now_us - start_us >= (uint64_t)timeout_us) {
            /* Checked after a pop, so bytes that arrived during the last wait
             * are still returned rather than reported as a timeout. */
            return 0;
        }
        if (uart->cfg->idle != NULL) {
            /* WFI or similar: the RX interrupt or the next tick wakes us. A
             * byte that lands just before the sleep waits at most one tick. */
            uart->cfg->idle(uart->cfg->hw);
        }
    }
}

static int uart_link_write(void *ctx, const uint8_t *buf, size_t len)
{
    rsm_uart_link_t *uart = (rsm_uart_link_t *)ctx;
    size_t i;
    if (len > (size_t)INT_MAX) {
        len = (size_t)INT_MAX;
    }
    for (i = 0; i < len; ++i) {
        const int status = uart->cfg->tx_byte(uart->cfg->hw, buf[i]);
        if (status < 0) {
            /* Report the bytes that did go out; the next call sees the error. */
            return i > 0u ? (int)i : status;
        }
    }
    return (int)len;
}

static int uart_link_set_baud(void *ctx, uint32_t baud)
{
    rsm_uart_link_t *uart = (rsm_uart_link_t *)ctx;
    if (uart->cfg->set_baud == NULL) {
        return RSM_ERR_NOSYS;
    }
    return uart->cfg->set_baud(uart->cfg->hw, baud);
}

static int uart_link_flush(void *ctx)
{
    rsm_uart_link_t *uart = (rsm_uart_link_t *)ctx;
    rsm_uart_ring_clear(uart->rx);
    return RSM_OK;
}

int rsm_uart_link_init(rsm_uart_link_t *uart, const rsm_uart_link_config_t *cfg,
                       rsm_uart_ring_t *rx, const rsm_clock_t *clock, rsm_link_t *link)
{
    if (uart == NULL || cfg == NULL || rx == NULL || clock == NULL || link == NULL ||
        cfg->tx_byte == NULL || clock->now_us == NULL) {
        return RSM_ERR_INVAL;
    }
    uart->cfg = cfg;
    uart->rx = rx;
    uart->clock = *clock;
    link->read = uart_link_read;
    link->write = uart_link_write;
    /* Leave set_baud NULL when the board cannot change it, so that callers
     * see RSM_ERR_NOSYS from rsm_link_set_baud as for any other port. */
    link->set_baud = cfg->set_baud != NULL ? uart_link_set_baud : NULL;
    link->flush = uart_link_flush;
    link->ctx = uart;
    return RSM_OK;
}
