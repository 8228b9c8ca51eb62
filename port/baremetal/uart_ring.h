/* Bare-metal UART receive path: a lock-free single-producer/single-consumer
 * byte ring that a receive interrupt fills and the main loop drains, and the
 * glue that presents a ring (plus a blocking transmit function) as an
 * rsm_link_t for the drivers.
 *
 *   UART RX interrupt --rsm_uart_ring_push()--> ring --rsm_link_read()--> driver
 *   driver --rsm_link_write_all()--> tx_byte() --> UART data register
 *
 * All state lives in caller-owned structs (typically static in the firmware's
 * main file); this module has no globals and never allocates.
 *
 * Concurrency model: exactly one producer (one interrupt handler, or one
 * thread) calls the *_push functions, and exactly one consumer (the main
 * loop) calls everything else. Under that rule no lock and no interrupt
 * masking is needed, provided that an aligned 32-bit load or store is atomic
 * on the target (true on every Cortex-M and 32-bit RISC-V; not on 8- or
 * 16-bit MCUs, which must mask the interrupt around the consumer calls). On a
 * single core, volatile accesses order the data byte before the index that
 * publishes it; on a multi-core part define RSM_UART_RING_BARRIER() as the
 * platform's data memory barrier (e.g. __DMB()).
 *
 * Overflow policy: when the ring is full an incoming byte is DROPPED (the
 * newest byte is lost, the oldest are kept) and counted in `overflows`.
 * Dropping the oldest instead would require the producer to move the
 * consumer's index, which is not lock-free. The codecs re-synchronise on
 * their sync bytes, so a gap costs at most the frame it falls in. */
#ifndef RSM_UART_RING_H
#define RSM_UART_RING_H

#include <stddef.h>
#include <stdint.h>

#include "rsm/config.h"
#include "rsm/hal.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Bytes each ring holds: a power of two, at least 2, at most 2^30. RAM cost:
 * this many bytes plus 12 per ring. Size it for the longest gap between two
 * main-loop reads at the line rate: 38400 baud delivers 3.84 bytes/ms, so the
 * default 1024 covers ~260 ms, one full LMS 0xB0 telegram (812 bytes) with
 * margin; a P3-DX SIP at 9600-115200 baud needs far less. Override it with
 * -DRSM_UART_RING_SIZE=... or in the RSM_USER_CONFIG header; the same value
 * must be seen by every file that includes this header. */
#ifndef RSM_UART_RING_SIZE
#define RSM_UART_RING_SIZE 1024
#endif

/* Ordering barrier between writing a byte and publishing it (and between
 * reading a byte and releasing its slot). Empty on a single core. */
#ifndef RSM_UART_RING_BARRIER
#define RSM_UART_RING_BARRIER() ((void)0)
#endif

RSM_STATIC_ASSERT(uart_ring_size_pow2,
                  RSM_UART_RING_SIZE >= 2 && RSM_UART_RING_SIZE <= (1L << 30) &&
                      (RSM_UART_RING_SIZE & (RSM_UART_RING_SIZE - 1)) == 0);

/* The ring. head and tail are free-running byte counts (they wrap modulo 2^32;
 * head - tail is the fill level because the size divides 2^32). Treat all
 * members as private: use the functions below. */
typedef struct rsm_uart_ring {
    volatile uint32_t head;      /* bytes ever pushed; written by the producer only */
    volatile uint32_t tail;      /* bytes ever popped or discarded; consumer only */
    volatile uint32_t overflows; /* bytes dropped because the ring was full; producer only */
    volatile uint8_t buf[RSM_UART_RING_SIZE];
} rsm_uart_ring_t;

/* Empties the ring and zeroes the overflow count. Call before the producer
 * is started (i.e. before enabling the UART interrupt). Not ISR-safe. */
void rsm_uart_ring_init(rsm_uart_ring_t *ring);

/* Producer side: appends one byte. Returns 1 if stored, 0 if the ring was
 * full (the byte is dropped and counted). ISR-safe; constant time; must only
 * be called by the single producer. */
int rsm_uart_ring_push(rsm_uart_ring_t *ring, uint8_t byte);

/* Producer side: appends up to n bytes from data (e.g. a hardware FIFO or a
 * DMA half-buffer). Bytes that do not fit are dropped and counted. Returns
 * the number stored. ISR-safe; producer only. data is not kept. */
size_t rsm_uart_ring_push_buf(rsm_uart_ring_t *ring, const uint8_t *data, size_t n);

/* Consumer side: moves up to cap of the oldest bytes into out and returns how
 * many (0 if the ring is empty). Never blocks. Consumer only. */
size_t rsm_uart_ring_pop(rsm_uart_ring_t *ring, uint8_t *out, size_t cap);

/* Consumer side: discards every byte received so far (bytes the producer
 * pushes concurrently may or may not survive). Consumer only. */
void rsm_uart_ring_clear(rsm_uart_ring_t *ring);

/* Bytes waiting to be popped, as seen at the moment of the call (the
 * producer may add more right after). Either side. */
size_t rsm_uart_ring_count(const rsm_uart_ring_t *ring);

/* Bytes dropped on overflow since init (wraps at 2^32). Either side. */
uint32_t rsm_uart_ring_overflows(const rsm_uart_ring_t *ring);

/* ---- the ring as an rsm_link_t -------------------------------------------- */

/* Sends one byte, blocking until the transmitter has accepted it (e.g. wait
 * for TXE, then write the data register). Returns RSM_OK or a negative status
 * (RSM_ERR_TIMEOUT if the transmitter is stuck). hw is the config's hw. */
typedef int (*rsm_uart_tx_byte_fn)(void *hw, uint8_t byte);

/* Reprograms the UART's baud rate divisor. Returns RSM_OK, RSM_ERR_RANGE if
 * the rate cannot be generated, or another negative status. */
typedef int (*rsm_uart_set_baud_fn)(void *hw, uint32_t baud);

/* Called while a read waits for bytes, e.g. to execute WFI and sleep until
 * the next interrupt (the UART or the tick). */
typedef void (*rsm_uart_idle_fn)(void *hw);

/* Board-specific, constant description of one UART; kept by pointer, so it
 * must outlive the link (make it static const). */
typedef struct rsm_uart_link_config {
    rsm_uart_tx_byte_fn tx_byte;   /* required */
    rsm_uart_set_baud_fn set_baud; /* optional: NULL -> rsm_link_set_baud gives RSM_ERR_NOSYS */
    rsm_uart_idle_fn idle;         /* optional: NULL -> busy-poll while waiting */
    void *hw;                      /* passed to the three functions above; not dereferenced */
} rsm_uart_link_config_t;

/* The link's state: which ring it reads, which clock times out reads. */
typedef struct rsm_uart_link {
    const rsm_uart_link_config_t *cfg; /* kept by pointer */
    rsm_uart_ring_t *rx;               /* kept by pointer; filled by the RX interrupt */
    rsm_clock_t clock;                 /* copied; its ctx must outlive the link */
} rsm_uart_link_t;

/* Binds a ring, a clock and a UART description into uart, and fills *link so
 * that rsm_link_read pops from the ring (waiting up to the timeout on the
 * clock), rsm_link_write_all calls tx_byte once per byte, rsm_link_flush
 * clears the ring and rsm_link_set_baud calls cfg->set_baud. link->ctx points
 * at uart, so uart must outlive link. The ring is not cleared (bytes that
 * arrived already stay readable). Returns RSM_OK, or RSM_ERR_INVAL (a NULL
 * argument, cfg->tx_byte NULL or clock->now_us NULL; nothing written). Not
 * ISR-safe; the resulting link must be used from the consumer side only. */
int rsm_uart_link_init(rsm_uart_link_t *uart, const rsm_uart_link_config_t *cfg,
                       rsm_uart_ring_t *rx, const rsm_clock_t *clock, rsm_link_t *link);

#ifdef __cplusplus
}
#endif

#endif /* RSM_UART_RING_H */
