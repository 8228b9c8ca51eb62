/* Board support for the Arm MPS2 with the AN386 image (Cortex-M4F at 25 MHz)
 * as QEMU's mps2-an386 machine emulates it. Addresses and interrupt numbers
 * are those of qemu hw/arm/mps2.c (the AN385 layout, which AN386 shares);
 * the peripherals are the Cortex-M System Design Kit's APB UART and APB timer
 * (Arm DDI 0479, CMSDK technical reference manual).
 *
 *   console  UART0 0x40004000 (QEMU's first -serial)
 *   robot    UART1 0x40005000, receive interrupt 2 (second -serial)
 *   laser    UART2 0x40006000, receive interrupt 4 (third -serial)
 *   cycles   TIMER0 0x40000000, a 32-bit down-counter at the 25 MHz SYSCLK;
 *            under QEMU's -icount shift=N the virtual clock advances 2^N ns
 *            per instruction, so one count is 40 / 2^N instructions.
 *   exit     semihosting SYS_EXIT (QEMU: -semihosting-config enable=on) */
#include <stddef.h>
#include <stdint.h>

#include "../board.h"
#include "rsm/status.h"

#define SYSCLK_HZ 25000000u
#define CONSOLE_BAUD 115200u

/* CMSDK APB UART */
typedef struct uart_regs {
    volatile uint32_t data;
    volatile uint32_t state;     /* bit 0 TX full, bit 1 RX full */
    volatile uint32_t ctrl;      /* bit 0 TX enable, 1 RX enable, 3 RX interrupt enable */
    volatile uint32_t intstatus; /* write 1 to clear */
    volatile uint32_t bauddiv;   /* SYSCLK / baud, at least 16 */
} uart_regs_t;

#define UART0 ((uart_regs_t *)0x40004000u)
#define UART1 ((uart_regs_t *)0x40005000u)
#define UART2 ((uart_regs_t *)0x40006000u)
#define UART_STATE_TXFULL (1u << 0)
#define UART_STATE_RXFULL (1u << 1)
#define UART_CTRL_TXEN (1u << 0)
#define UART_CTRL_RXEN (1u << 1)
#define UART_CTRL_RXIE (1u << 3)
#define UART_INT_RX (1u << 1)
#define UART_TX_SPIN_LIMIT 100000u

/* CMSDK APB timer */
typedef struct timer_regs {
    volatile uint32_t ctrl; /* bit 0 enable */
    volatile uint32_t value;
    volatile uint32_t reload;
    volatile uint32_t intstatus;
} timer_regs_t;

#define TIMER0 ((timer_regs_t *)0x40000000u)

/* Architectural Cortex-M registers (ARMv7-M ARM, B3.3 SysTick, B3.4 NVIC). */
#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)
#define NVIC_ISER0 (*(volatile uint32_t *)0xE000E100u)

#define IRQ_UART1_RX 2u
#define IRQ_UART2_RX 4u

/* The AN385 image is the same board with a Cortex-M3 (no FPU): QEMU's
 * mps2-an385 machine, on which the soft-float images run, has the same
 * memory map and devices. */
#if defined(__ARM_FP)
const char rsm_board_name[] = "mps2-an386";
#else
const char rsm_board_name[] = "mps2-an385";
#endif

uint32_t rsm_board_core_hz(void)
{
    return SYSCLK_HZ;
}

void rsm_board_init(void)
{
    UART0->bauddiv = SYSCLK_HZ / CONSOLE_BAUD;
    UART0->ctrl = UART_CTRL_TXEN;
    TIMER0->ctrl = 0u;
    TIMER0->reload = 0xFFFFFFFFu;
    TIMER0->value = 0xFFFFFFFFu;
    TIMER0->ctrl = 1u;
}

void rsm_board_console_write(const char *s, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        while ((UART0->state & UART_STATE_TXFULL) != 0u) {
        }
        UART0->data = (uint8_t)s[i];
    }
}

uint32_t rsm_board_cycles(void)
{
    return 0xFFFFFFFFu - TIMER0->value; /* counts up */
}

uint32_t rsm_board_cycles_hz(void)
{
    return SYSCLK_HZ;
}

void *rsm_board_port_hw(rsm_board_port_t port)
{
    return port == RSM_BOARD_PORT_ROBOT ? (void *)UART1 : (void *)UART2;
}

int rsm_board_uart_tx_byte(void *hw, uint8_t byte)
{
    uart_regs_t *u = (uart_regs_t *)hw;
    uint32_t spins = UART_TX_SPIN_LIMIT;
    while ((u->state & UART_STATE_TXFULL) != 0u) {
        if (--spins == 0u) {
            return RSM_ERR_TIMEOUT;
        }
    }
    u->data = byte;
    return RSM_OK;
}

int rsm_board_uart_set_baud(void *hw, uint32_t baud)
{
    uart_regs_t *u = (uart_regs_t *)hw;
    uint32_t div;
    if (baud == 0u) {
        return RSM_ERR_RANGE;
    }
    div = (SYSCLK_HZ + baud / 2u) / baud;
    if (div < 16u || div > 0xFFFFFu) {
        return RSM_ERR_RANGE;
    }
    u->bauddiv = div;
    u->ctrl = UART_CTRL_TXEN | UART_CTRL_RXEN | UART_CTRL_RXIE;
    return RSM_OK;
}

int rsm_board_uart_rx_byte(void *hw, uint8_t *byte)
{
    uart_regs_t *u = (uart_regs_t *)hw;
    if ((u->state & UART_STATE_RXFULL) == 0u) {
        u->intstatus = UART_INT_RX;
        return 0;
    }
    *byte = (uint8_t)(u->data & 0xFFu);
    u->intstatus = UART_INT_RX;
    return 1;
}

void rsm_board_start_interrupts(void)
{
    SYST_RVR = SYSCLK_HZ / 1000u - 1u;
    SYST_CVR = 0u;
    SYST_CSR = 7u; /* core clock, interrupt, enable */
    NVIC_ISER0 = (1u << IRQ_UART1_RX) | (1u << IRQ_UART2_RX);
}

void rsm_board_idle(void *hw)
{
    (void)hw;
    __asm__ volatile("wfi");
}

void rsm_board_exit(int status)
{
    /* Semihosting SYS_EXIT (0x18) with ADP_Stopped_ApplicationExit (0x20026)
     * or ADP_Stopped_RunTimeErrorUnknown (0x20023): "Semihosting for AArch32
     * and AArch64", Arm. QEMU exits 0 for the first, 1 otherwise. */
    register uint32_t op __asm__("r0") = 0x18u;
    register uint32_t arg __asm__("r1") = status == 0 ? 0x20026u : 0x20023u;
    __asm__ volatile("bkpt 0xab" : : "r"(op), "r"(arg) : "memory");
    for (;;) {
    }
}

/* ---- vector table ---------------------------------------------------------- */

static void uart1_isr(void)
{
    rsm_app_uart_isr(RSM_BOARD_PORT_ROBOT);
}

static void uart2_isr(void)
{
    rsm_app_uart_isr(RSM_BOARD_PORT_LASER);
}

#define DEFAULT RSM_BOARD_DEFAULT_VECTOR

/* 16 system exceptions, then the board's 32 interrupts (UART1 RX is 2, UART2
 * RX 4). */
__attribute__((section(".vectors"), used)) const rsm_vector_t rsm_vectors[16 + 32] = {
    RSM_BOARD_SYSTEM_VECTORS,
    DEFAULT, DEFAULT, {.handler = uart1_isr}, DEFAULT, {.handler = uart2_isr}, DEFAULT, DEFAULT, DEFAULT,
    DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT,
    DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT,
    DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT,
};
