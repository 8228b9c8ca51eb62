/* Example firmware main for a Cortex-M4F board: a template, and the image that
 * tools/cross-check measures to report what linking rsm costs.
 *
 * This file is the APPLICATION, not the library: it owns every piece of rsm
 * state, statically, at file scope (the library itself keeps none), and it is
 * the only place where interrupt handlers may reach that state directly.
 *
 * What it does today: sets up a millisecond tick clock, two UART receive
 * rings filled from their interrupts, and two rsm_link_t on top of them (the
 * Pioneer P3-DX on one UART, the SICK LMS 2xx on the other), then drains both
 * links in the main loop, counting bytes. The ARIA and LMS drivers and the
 * localizer slot into the places marked ">>> RSM_FIRMWARE" below.
 *
 * The register layout is a PLACEHOLDER in the style of an STM32F4 USART
 * (SR/DR/BRR/CR1, RXNE and TXE flags) at made-up board addresses; SysTick is
 * the architectural Cortex-M one. Replace everything under "board
 * placeholders" with your vendor's headers and startup code, whose vector
 * table must point at the handlers defined here. */
#include <stddef.h>
#include <stdint.h>

#include "rsm/hal.h"
#include "rsm/localizer.h"
#include "rsm/p3dx.h"
#include "rsm/sicklms.h"
#include "rsm/status.h"
#include "rsm/sync.h"
#include "tick_clock.h"
#include "uart_ring.h"

/* ---- board placeholders --------------------------------------------------- */

typedef struct fw_usart_regs {
    volatile uint32_t sr;  /* status: RXNE = byte received, TXE = data register empty */
    volatile uint32_t dr;  /* data */
    volatile uint32_t brr; /* baud rate divisor = peripheral clock / baud */
    volatile uint32_t cr1; /* control: UE, TE, RE, RXNEIE */
} fw_usart_regs_t;

#define FW_USART_ROBOT ((fw_usart_regs_t *)0x40011000u) /* placeholder: P3-DX port */
#define FW_USART_LASER ((fw_usart_regs_t *)0x40004400u) /* placeholder: LMS port */
#define FW_SR_RXNE (1u << 5)
#define FW_SR_TC (1u << 6)
#define FW_SR_TXE (1u << 7)
#define FW_CR1_RE (1u << 2)
#define FW_CR1_TE (1u << 3)
#define FW_CR1_RXNEIE (1u << 5)
#define FW_CR1_UE (1u << 13)
#define FW_PCLK_HZ 84000000u  /* placeholder: the UARTs' peripheral clock */
#define FW_CORE_HZ 168000000u /* placeholder: the core clock that drives SysTick */
#define FW_TX_SPIN_LIMIT 100000u

/* SysTick (architectural on every ARMv7-M core). */
#define FW_SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define FW_SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define FW_SYST_CVR (*(volatile uint32_t *)0xE000E018u)

/* ---- the application's state (caller-owned rsm state, static here) -------- */

/* Milliseconds since reset; written only by SysTick_Handler. */
static volatile uint32_t fw_ms_ticks;

static rsm_tick_clock_t fw_tick;          /* 64-bit microseconds from fw_ms_ticks */
static rsm_clock_t fw_clock;              /* fw_tick as an rsm_clock_t */
static rsm_uart_ring_t fw_robot_rx;       /* filled by USART1_IRQHandler */
static rsm_uart_ring_t fw_laser_rx;       /* filled by USART2_IRQHandler */
static rsm_uart_link_t fw_robot_uart;
static rsm_uart_link_t fw_laser_uart;
static rsm_link_t fw_robot_link;          /* hand this to the ARIA driver */
static rsm_link_t fw_laser_link;          /* hand this to the LMS driver */

/* Counters for a debugger or a telemetry frame (count, don't print). */
static struct fw_stats {
    uint32_t robot_overflows;
    uint32_t laser_overflows;
} fw_stats;

/* The two device drivers and the localizer they feed. */
static rsm_localizer_config_t fw_loc_cfg;
static rsm_localizer_t fw_localizer;
static rsm_sync_config_t fw_sync_cfg;
static rsm_sync_t fw_sync;                /* fuses each scan with odometry at its own time */
static rsm_p3dx_config_t fw_robot_cfg;
static rsm_p3dx_t fw_robot;
static rsm_sicklms_config_t fw_laser_cfg;
static rsm_sicklms_t fw_laser;

/* ---- board functions behind the HAL ---------------------------------------- */

static uint32_t fw_read_ms(void *hw)
{
    (void)hw;
    return fw_ms_ticks;
}

static int fw_uart_tx_byte(void *hw, uint8_t byte)
{
    fw_usart_regs_t *usart = (fw_usart_regs_t *)hw;
    uint32_t spins = FW_TX_SPIN_LIMIT;
    while ((usart->sr & FW_SR_TXE) == 0u) {
        if (--spins == 0u) {
            return RSM_ERR_TIMEOUT;
        }
    }
    usart->dr = byte;
    return RSM_OK;
}

static int fw_uart_set_baud(void *hw, uint32_t baud)
{
    fw_usart_regs_t *usart = (fw_usart_regs_t *)hw;
    const uint32_t div = (FW_PCLK_HZ + baud / 2u) / baud;
    uint32_t spins = FW_TX_SPIN_LIMIT;
    if (div < 16u || div > 0xFFFFu) {
        return RSM_ERR_RANGE;
    }
    /* The last byte written (e.g. the P3-DX's HOSTBAUD) leaves at the old
     * rate first (hal.h): wait for transmission complete. */
    while ((usart->sr & FW_SR_TC) == 0u && --spins != 0u) {
    }
    usart->brr = div;
    return RSM_OK;
}

static void fw_idle(void *hw)
{
    (void)hw;
    /* Sleep until the next interrupt: a received byte or the 1 ms tick. */
    __asm__ volatile("wfi");
}

static const rsm_tick_clock_config_t fw_tick_cfg = {
    fw_read_ms, NULL, 1000u, 32u
};
static const rsm_uart_link_config_t fw_robot_uart_cfg = {
    fw_uart_tx_byte, fw_uart_set_baud, fw_idle, (void *)FW_USART_ROBOT
};
static const rsm_uart_link_config_t fw_laser_uart_cfg = {
    fw_uart_tx_byte, fw_uart_set_baud, fw_idle, (void *)FW_USART_LASER
};

/* ---- interrupt handlers (the vector table points here) ---------------------- */

void SysTick_Handler(void);
void USART1_IRQHandler(void);
void USART2_IRQHandler(void);

void SysTick_Handler(void)
{
    fw_ms_ticks = fw_ms_ticks + 1u;
}

/* Moves every byte the UART holds into the ring; the ring is the only state
 * shared with the main loop, and the ISR is its only producer. */
static void fw_uart_rx_isr(fw_usart_regs_t *usart, rsm_uart_ring_t *ring)
{
    while ((usart->sr & FW_SR_RXNE) != 0u) {
        (void)rsm_uart_ring_push(ring, (uint8_t)(usart->dr & 0xFFu));
    }
}

void USART1_IRQHandler(void)
{
    fw_uart_rx_isr(FW_USART_ROBOT, &fw_robot_rx);
}

void USART2_IRQHandler(void)
{
    fw_uart_rx_isr(FW_USART_LASER, &fw_laser_rx);
}

/* ---- start-up and main loop ------------------------------------------------- */

static void fw_board_init(void)
{
    FW_SYST_RVR = FW_CORE_HZ / 1000u - 1u; /* 1 kHz tick */
    FW_SYST_CVR = 0u;
    FW_SYST_CSR = 7u; /* core clock, interrupt, enable */
    FW_USART_ROBOT->cr1 = FW_CR1_UE | FW_CR1_TE | FW_CR1_RE | FW_CR1_RXNEIE;
    FW_USART_LASER->cr1 = FW_CR1_UE | FW_CR1_TE | FW_CR1_RE | FW_CR1_RXNEIE;
    /* Placeholder: enable the two USART interrupts in the NVIC here. */
}

int main(void)
{
    uint64_t now_us = 0u;

    /* Rings first: the interrupts that fill them are enabled by fw_board_init. */
    rsm_uart_ring_init(&fw_robot_rx);
    rsm_uart_ring_init(&fw_laser_rx);
    if (rsm_tick_clock_init(&fw_tick, &fw_tick_cfg, &fw_clock) != RSM_OK ||
        rsm_uart_link_init(&fw_robot_uart, &fw_robot_uart_cfg, &fw_robot_rx, &fw_clock,
                           &fw_robot_link) != RSM_OK ||
        rsm_uart_link_init(&fw_laser_uart, &fw_laser_uart_cfg, &fw_laser_rx, &fw_clock,
                           &fw_laser_link) != RSM_OK) {
        for (;;) {
            /* A configuration error: stop here, where a debugger will look. */
        }
    }
    fw_board_init();
    /* P3-DX and LMS 2xx both power up at 9600 baud. */
    (void)rsm_link_set_baud(&fw_robot_link, 9600u);
    (void)rsm_link_set_baud(&fw_laser_link, 9600u);

    /* >>> RSM_FIRMWARE_INIT: initialise the drivers on fw_robot_link and
     *     fw_laser_link with fw_clock here. */
    {
        const rsm_pose_t start = {0.0f, 0.0f, 0.0f};
        fw_loc_cfg = rsm_localizer_config_default();
        (void)rsm_p3dx_config_default(&fw_robot_cfg);
        (void)rsm_sicklms_config_default(&fw_laser_cfg);
        fw_laser_cfg.baud = 38400u; /* switch the laser up from its power-up 9600 */
        fw_sync_cfg = rsm_sync_config_default();
        if (rsm_localizer_init(&fw_localizer, &fw_loc_cfg, &start, NULL) != RSM_OK ||
            rsm_sync_init(&fw_sync, &fw_localizer, &fw_sync_cfg, NULL, NULL) != RSM_OK ||
            rsm_p3dx_init(&fw_robot, &fw_robot_link, &fw_clock, &fw_robot_cfg) != RSM_OK ||
            rsm_sicklms_init(&fw_laser, &fw_laser_link, &fw_clock, &fw_laser_cfg) != RSM_OK ||
            rsm_p3dx_connect(&fw_robot) != RSM_OK || rsm_sicklms_connect(&fw_laser) != RSM_OK) {
            for (;;) {
            }
        }
    }

    for (;;) {
        int moved = 0;
        /* Keeps the tick clock's 64-bit extension current, and is the time
         * base for everything below. */
        (void)rsm_clock_now_us(&fw_clock, &now_us);

        /* The drivers read their links themselves, never waiting longer
         * than their read timeout; their events feed the localizer. */
        {
            rsm_p3dx_event_t rev;
            rsm_sicklms_event_t lev;
            if (rsm_p3dx_poll(&fw_robot, &rev) == RSM_OK && rev.type == RSM_P3DX_EVENT_ENCODER) {
                (void)rsm_sync_encoder(&fw_sync, (uint32_t)rev.encoder.left, (uint32_t)rev.encoder.right,
                                       rev.stamp_us);
                moved = 1;
            }
            if (rsm_sicklms_poll(&fw_laser, &lev) == RSM_OK && lev.type == RSM_SICKLMS_EVENT_SCAN &&
                lev.scan != NULL) {
                (void)rsm_sync_scan(&fw_sync, lev.scan);
                moved = 1;
            }
        }

        (void)rsm_sync_poll(&fw_sync, now_us); /* a scan waits at most max_wait_us for odometry */
        fw_stats.robot_overflows = rsm_uart_ring_overflows(&fw_robot_rx);
        fw_stats.laser_overflows = rsm_uart_ring_overflows(&fw_laser_rx);
        if (moved == 0) {
            fw_idle(NULL);
        }
    }
}
