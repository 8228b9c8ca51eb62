#include "fakelink.h"

#include <string.h>

#include "rsm/status.h"

/* Bytes received at the wrong rate: a deterministic mangling whose results
 * (0xE0..0xEF) are never a sync, STX, ACK or NAK byte, so a garbled stream
 * cannot be mistaken for a valid answer. */
static uint8_t garble(uint8_t b)
{
    return (uint8_t)(0xE0u | (b & 0x0Fu));
}

static int fl_read(void *ctx, uint8_t *buf, size_t cap, uint32_t timeout_us)
{
    rsm_fakelink_t *fl = (rsm_fakelink_t *)ctx;
    const uint64_t start = fl->now_us;
    size_t n = 0u;
    fl->reads++;
    if (timeout_us > fl->max_read_timeout_us) {
        fl->max_read_timeout_us = timeout_us;
    }
    if (cap == 0u) {
        return 0;
    }
    if (fl->rx_len == 0u || fl->rx_at[0] > fl->now_us + timeout_us) {
        fl->now_us += timeout_us;
    } else if (fl->rx_at[0] > fl->now_us) {
        fl->now_us = fl->rx_at[0];
    }
    if (fl->now_us - start > fl->max_read_wait_us) {
        fl->max_read_wait_us = fl->now_us - start;
    }
    while (n < cap && n < fl->rx_len && fl->rx_at[n] <= fl->now_us) {
        n++;
    }
    if (n > 0u) {
        memcpy(buf, fl->rx, n);
        memmove(fl->rx, fl->rx + n, fl->rx_len - n);
        memmove(fl->rx_at, fl->rx_at + n, (fl->rx_len - n) * sizeof fl->rx_at[0]);
        fl->rx_len -= n;
    }
    return (int)n;
}

static int fl_write(void *ctx, const uint8_t *buf, size_t len)
{
    rsm_fakelink_t *fl = (rsm_fakelink_t *)ctx;
    uint8_t seen[512];
    size_t i;
    size_t n = len > sizeof seen ? sizeof seen : len;
    if (fl->n_writes < RSM_FAKELINK_MAX_WRITES) {
        fl->writes[fl->n_writes].at_us = fl->now_us;
        fl->writes[fl->n_writes].offset = fl->host_log_len;
        fl->writes[fl->n_writes].len = n;
        fl->n_writes++;
    }
    for (i = 0u; i < n; i++) {
        if (fl->host_log_len < RSM_FAKELINK_LOG_CAP) {
            fl->host_log[fl->host_log_len++] = buf[i];
        }
        seen[i] = fl->host_baud == fl->peer_baud ? buf[i] : garble(buf[i]);
    }
    if (fl->peer != NULL && !fl->silent) {
        fl->peer(fl, seen, n, fl->peer_user);
    }
    return (int)n;
}

static int fl_set_baud(void *ctx, uint32_t baud)
{
    rsm_fakelink_t *fl = (rsm_fakelink_t *)ctx;
    fl->set_baud_calls++;
    if (baud != 9600u && baud != 19200u && baud != 38400u && baud != 57600u && baud != 115200u &&
        baud != 230400u && baud != 256000u && baud != 460800u && baud != 500000u) {
        return RSM_ERR_RANGE;
    }
    fl->host_baud = baud;
    return RSM_OK;
}

static int fl_flush(void *ctx)
{
    rsm_fakelink_t *fl = (rsm_fakelink_t *)ctx;
    size_t n = 0u;
    fl->flushes++;
    /* Only bytes that have already arrived are discarded. */
    while (n < fl->rx_len && fl->rx_at[n] <= fl->now_us) {
        n++;
    }
    memmove(fl->rx, fl->rx + n, fl->rx_len - n);
    memmove(fl->rx_at, fl->rx_at + n, (fl->rx_len - n) * sizeof fl->rx_at[0]);
    fl->rx_len -= n;
    return RSM_OK;
}

static uint64_t fl_now(void *ctx)
{
    return ((rsm_fakelink_t *)ctx)->now_us;
}

void rsm_fakelink_init(rsm_fakelink_t *fl, uint64_t start_us, rsm_link_t *link, rsm_clock_t *clock)
{
    memset(fl, 0, sizeof *fl);
    fl->now_us = start_us;
    fl->host_baud = 9600u;
    fl->peer_baud = 9600u;
    fl->has_set_baud = 1;
    fl->flip_index = -1;
    if (link != NULL) {
        link->read = fl_read;
        link->write = fl_write;
        link->set_baud = fl_set_baud;
        link->flush = fl_flush;
        link->ctx = fl;
    }
    if (clock != NULL) {
        clock->now_us = fl_now;
        clock->ctx = fl;
    }
}

void rsm_fakelink_set_peer(rsm_fakelink_t *fl, rsm_fakelink_peer_fn peer, void *user)
{
    fl->peer = peer;
    fl->peer_user = user;
}

static void queue(rsm_fakelink_t *fl, uint8_t b, uint64_t at)
{
    if (at < fl->last_arrival_us) {
        at = fl->last_arrival_us;
    }
    fl->last_arrival_us = at;
    if (fl->rx_len < RSM_FAKELINK_RX_CAP) {
        fl->rx[fl->rx_len] = b;
        fl->rx_at[fl->rx_len] = at;
        fl->rx_len++;
    }
    if (fl->peer_log_len < RSM_FAKELINK_LOG_CAP) {
        fl->peer_log[fl->peer_log_len++] = b;
    }
}

void rsm_fakelink_send(rsm_fakelink_t *fl, const uint8_t *data, size_t len, uint32_t delay_us)
{
    size_t i;
    if (fl->silent) {
        return;
    }
    for (i = 0u; i < len; i++) {
        uint8_t b = data[i];
        if (fl->drop_next > 0u) {
            fl->drop_next--;
            continue;
        }
        if (fl->flip_index == 0) {
            b ^= 0x01u;
        }
        if (fl->flip_index >= 0) {
            fl->flip_index--;
        }
        if (fl->host_baud != fl->peer_baud) {
            b = garble(b);
        }
        queue(fl, b, fl->now_us + delay_us);
    }
}

void rsm_fakelink_inject(rsm_fakelink_t *fl, const uint8_t *data, size_t len, uint32_t delay_us)
{
    size_t i;
    for (i = 0u; i < len; i++) {
        queue(fl, data[i], fl->now_us + delay_us);
    }
}

void rsm_fakelink_set_peer_baud(rsm_fakelink_t *fl, uint32_t baud)
{
    fl->peer_baud = baud;
}

void rsm_fakelink_advance(rsm_fakelink_t *fl, uint64_t us)
{
    fl->now_us += us;
}

size_t rsm_fakelink_count_host(const rsm_fakelink_t *fl, size_t from, const uint8_t *pattern,
                               size_t len)
{
    size_t count = 0u;
    size_t i;
    if (len == 0u || fl->host_log_len < len) {
        return 0u;
    }
    for (i = from; i + len <= fl->host_log_len; i++) {
        if (memcmp(fl->host_log + i, pattern, len) == 0) {
            count++;
        }
    }
    return count;
}

long rsm_fakelink_find_write(const rsm_fakelink_t *fl, size_t from, const uint8_t *pattern,
                             size_t len)
{
    size_t i;
    for (i = from; i < fl->n_writes; i++) {
        if (fl->writes[i].len == len &&
            memcmp(fl->host_log + fl->writes[i].offset, pattern, len) == 0) {
            return (long)i;
        }
    }
    return -1;
}
