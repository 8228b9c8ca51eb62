/* Board support for an RP2040 (Raspberry Pi Pico and its kin: two Cortex-M0+
 * cores, no FPU, 264 KiB of SRAM, external QSPI flash) at 125 MHz from a
 * 12 MHz crystal. Register addresses and bits are those of the RP2040
 * datasheet (Raspberry Pi Ltd); docs/bringup-rp2040.md explains the choices.
 * Core 0 runs everything; core 1 sleeps in the boot ROM.
 *
 *   clocks   XOSC 12 MHz -> PLL_SYS (refdiv 1, fbdiv 125, post 6 x 2):
 *            clk_sys 125 MHz; clk_ref and the timer's 1 MHz tick from the
 *            XOSC; clk_peri (the UARTs) from clk_sys
 *   robot    UART0: TX GP0, RX GP1, interrupt 20
 *   laser    UART1: RX GP5 (the LD06's TX), interrupt 21
 *   console  UART1 TX GP4: the LD06 takes no commands, so its port's
 *            transmit side is free; it runs at the LD06's 230400 baud
 *   cycles   the TIMER's microsecond counter (an M0+ has no DWT cycle counter)
 * Only linked by ./tools/test (no emulator here runs it); untested on a
 * board: see the bring-up note. */
#include <stddef.h>
#include <stdint.h>

#include "../board.h"
#include "rsm/status.h"

#define XOSC_HZ 12000000u
#define CORE_HZ 125000000u
#define PERI_HZ CORE_HZ
#define TIMER_HZ 1000000u

#define REG(addr) (*(volatile uint32_t *)(addr))
/* Every peripheral register has atomic aliases: +0x2000 sets bits, +0x3000
 * clears them (datasheet 2.1.2). */
#define SET(addr) REG((addr) + 0x2000u)
#define CLR(addr) REG((addr) + 0x3000u)

/* Resets (datasheet 2.14) */
#define RESETS 0x4000C000u
#define RESETS_RESET (RESETS + 0x0u)
#define RESETS_DONE REG(RESETS + 0x8u)
#define RST_IO_BANK0 (1u << 5)
#define RST_PADS_BANK0 (1u << 8)
#define RST_PLL_SYS (1u << 12)
#define RST_TIMER (1u << 21)
#define RST_UART0 (1u << 22)
#define RST_UART1 (1u << 23)

/* Crystal oscillator (2.16), PLL (2.18), clocks (2.15), watchdog tick (4.7) */
#define XOSC_CTRL REG(0x40024000u)
#define XOSC_STATUS REG(0x40024004u)
#define XOSC_STARTUP REG(0x4002400Cu)
#define XOSC_CTRL_1_15MHZ 0xAA0u
#define XOSC_CTRL_ENABLE (0xFABu << 12)
#define XOSC_STATUS_STABLE (1u << 31)
#define PLL_SYS 0x40028000u
#define PLL_CS REG(PLL_SYS + 0x0u)
#define PLL_PWR (PLL_SYS + 0x4u)
#define PLL_FBDIV REG(PLL_SYS + 0x8u)
#define PLL_PRIM REG(PLL_SYS + 0xCu)
#define PLL_CS_LOCK (1u << 31)
#define PLL_PWR_PD (1u << 0)
#define PLL_PWR_POSTDIVPD (1u << 3)
#define PLL_PWR_VCOPD (1u << 5)
#define CLOCKS 0x40008000u
#define CLK_REF_CTRL REG(CLOCKS + 0x30u)
#define CLK_REF_SELECTED REG(CLOCKS + 0x38u)
#define CLK_SYS_CTRL REG(CLOCKS + 0x3Cu)
#define CLK_SYS_SELECTED REG(CLOCKS + 0x44u)
#define CLK_PERI_CTRL REG(CLOCKS + 0x48u)
#define CLK_REF_SRC_XOSC 2u
#define CLK_SYS_SRC_AUX 1u /* its auxiliary source, whose default is PLL_SYS */
#define CLK_PERI_ENABLE (1u << 11) /* auxiliary source 0: clk_sys */
#define WATCHDOG_TICK REG(0x4005802Cu)
#define WATCHDOG_TICK_ENABLE (1u << 9)

/* GPIO function select (2.19) */
#define IO_BANK0_CTRL(n) REG(0x40014004u + 8u * (n))
#define FUNC_UART 2u

/* Timer (4.6): the 64-bit microsecond counter's low word, read without latching */
#define TIMER_RAWL REG(0x40054028u)

/* PL011 UARTs (4.2) */
typedef struct uart_regs {
    volatile uint32_t dr;
    volatile uint32_t rsr;
    uint32_t reserved0[4];
    volatile uint32_t fr; /* bit 4 RX FIFO empty, bit 5 TX FIFO full */
    uint32_t reserved1;
    volatile uint32_t ilpr;
    volatile uint32_t ibrd;
    volatile uint32_t fbrd;
    volatile uint32_t lcr_h;
    volatile uint32_t cr;
    volatile uint32_t ifls;
    volatile uint32_t imsc;
    volatile uint32_t ris;
    volatile uint32_t mis;
    volatile uint32_t icr;
} uart_regs_t;

#define UART0 ((uart_regs_t *)0x40034000u)
#define UART1 ((uart_regs_t *)0x40038000u)
#define UART_FR_RXFE (1u << 4)
#define UART_FR_TXFF (1u << 5)
#define UART_LCR_H_8N1_FIFO ((3u << 5) | (1u << 4))
#define UART_CR_ON ((1u << 0) | (1u << 8) | (1u << 9))
#define UART_IMSC_RX ((1u << 4) | (1u << 6)) /* FIFO level and receive time-out */
#define UART_TX_SPIN_LIMIT 100000u
#define CONSOLE_BAUD 230400u

/* Architectural Cortex-M0+ registers (ARMv6-M ARM, B3.3 SysTick, B3.4 NVIC) */
#define SYST_CSR REG(0xE000E010u)
#define SYST_RVR REG(0xE000E014u)
#define SYST_CVR REG(0xE000E018u)
#define NVIC_ISER REG(0xE000E100u)

#define IRQ_UART0 20u
#define IRQ_UART1 21u

const char rsm_board_name[] = "rp2040";

uint32_t rsm_board_core_hz(void)
{
    return CORE_HZ;
}

static void unreset(uint32_t bits)
{
    CLR(RESETS_RESET) = bits;
    while ((RESETS_DONE & bits) != bits) {
    }
}

static void clocks_init(void)
{
    XOSC_CTRL = XOSC_CTRL_1_15MHZ;
    XOSC_STARTUP = (XOSC_HZ / 1000u + 128u) / 256u; /* about 1 ms, in units of 256 cycles */
    XOSC_CTRL = XOSC_CTRL_1_15MHZ | XOSC_CTRL_ENABLE;
    while ((XOSC_STATUS & XOSC_STATUS_STABLE) == 0u) {
    }
    /* clk_ref on the crystal, clk_sys on clk_ref while the PLL starts. */
    CLK_REF_CTRL = CLK_REF_SRC_XOSC;
    while (CLK_REF_SELECTED != (1u << CLK_REF_SRC_XOSC)) {
    }
    CLK_SYS_CTRL = 0u;
    while (CLK_SYS_SELECTED != 1u) {
    }
    unreset(RST_PLL_SYS);
    PLL_CS = 1u;     /* refdiv */
    PLL_FBDIV = 125u; /* VCO 1500 MHz */
    CLR(PLL_PWR) = PLL_PWR_PD | PLL_PWR_VCOPD;
    while ((PLL_CS & PLL_CS_LOCK) == 0u) {
    }
    PLL_PRIM = (6u << 16) | (2u << 12); /* 1500 / 6 / 2 = 125 MHz */
    CLR(PLL_PWR) = PLL_PWR_POSTDIVPD;
    CLK_SYS_CTRL = CLK_SYS_SRC_AUX;
    while (CLK_SYS_SELECTED != 2u) {
    }
    CLK_PERI_CTRL = CLK_PERI_ENABLE;
    /* The timer counts microseconds of the watchdog's tick, from clk_ref. */
    WATCHDOG_TICK = (XOSC_HZ / TIMER_HZ) | WATCHDOG_TICK_ENABLE;
}

/* PL011 divisor: clk_peri / (16 baud) as 16.6 fixed point, rounded. */
static int uart_divisor(uart_regs_t *u, uint32_t baud)
{
    uint32_t div64;
    if (baud == 0u || baud > PERI_HZ / 16u) {
        return RSM_ERR_RANGE;
    }
    div64 = (uint32_t)(((uint64_t)PERI_HZ * 4u + baud / 2u) / baud); /* 64 PERI / (16 baud) */
    if ((div64 >> 6) == 0u || (div64 >> 6) > 0xFFFFu) {
        return RSM_ERR_RANGE;
    }
    u->cr = 0u;
    u->ibrd = div64 >> 6;
    u->fbrd = div64 & 63u;
    u->lcr_h = UART_LCR_H_8N1_FIFO; /* also latches the divisor */
    u->cr = UART_CR_ON;
    return RSM_OK;
}

void rsm_board_init(void)
{
    clocks_init();
    unreset(RST_IO_BANK0 | RST_PADS_BANK0 | RST_TIMER | RST_UART0 | RST_UART1);
    IO_BANK0_CTRL(0u) = FUNC_UART;
    IO_BANK0_CTRL(1u) = FUNC_UART;
    IO_BANK0_CTRL(4u) = FUNC_UART;
    IO_BANK0_CTRL(5u) = FUNC_UART;
    (void)uart_divisor(UART1, CONSOLE_BAUD);
}

void rsm_board_console_write(const char *s, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        while ((UART1->fr & UART_FR_TXFF) != 0u) {
        }
        UART1->dr = (uint8_t)s[i];
    }
}

uint32_t rsm_board_cycles(void)
{
    return TIMER_RAWL;
}

uint32_t rsm_board_cycles_hz(void)
{
    return TIMER_HZ;
}

void *rsm_board_port_hw(rsm_board_port_t port)
{
    return port == RSM_BOARD_PORT_ROBOT ? (void *)UART0 : (void *)UART1;
}

int rsm_board_uart_tx_byte(void *hw, uint8_t byte)
{
    uart_regs_t *u = (uart_regs_t *)hw;
    uint32_t spins = UART_TX_SPIN_LIMIT;
    while ((u->fr & UART_FR_TXFF) != 0u) {
        if (--spins == 0u) {
            return RSM_ERR_TIMEOUT;
        }
    }
    u->dr = byte;
    return RSM_OK;
}

int rsm_board_uart_set_baud(void *hw, uint32_t baud)
{
    uart_regs_t *u = (uart_regs_t *)hw;
    const int rc = uart_divisor(u, baud);
    if (rc == RSM_OK) {
        u->imsc = UART_IMSC_RX;
    }
    return rc;
}

int rsm_board_uart_rx_byte(void *hw, uint8_t *byte)
{
    uart_regs_t *u = (uart_regs_t *)hw;
    if ((u->fr & UART_FR_RXFE) != 0u) {
        return 0; /* reading the FIFO empty clears the interrupt */
    }
    *byte = (uint8_t)(u->dr & 0xFFu);
    return 1;
}

void rsm_board_start_interrupts(void)
{
    SYST_RVR = CORE_HZ / 1000u - 1u;
    SYST_CVR = 0u;
    SYST_CSR = 7u; /* core clock, interrupt, enable */
    NVIC_ISER = (1u << IRQ_UART0) | (1u << IRQ_UART1);
}

/* ---- vector table ---------------------------------------------------------- */

static void uart0_isr(void)
{
    rsm_app_uart_isr(RSM_BOARD_PORT_ROBOT);
}

static void uart1_isr(void)
{
    rsm_app_uart_isr(RSM_BOARD_PORT_LASER);
}

#define DEFAULT RSM_BOARD_DEFAULT_VECTOR

/* 16 system exceptions (the M0+ has no MemManage, BusFault or UsageFault:
 * those entries are never taken), then the RP2040's 26 interrupts and 6
 * unused: UART0 is 20, UART1 21. Placed after the 256-byte second-stage
 * boot loader, where it jumps (link.ld). */
__attribute__((section(".vectors"), used)) const rsm_vector_t rsm_vectors[16 + 32] = {
    RSM_BOARD_SYSTEM_VECTORS,
    DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT,
    DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT,
    DEFAULT, DEFAULT, DEFAULT, DEFAULT, {.handler = uart0_isr}, {.handler = uart1_isr}, DEFAULT, DEFAULT,
    DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT,
};
