/* Board support for an STM32F407 at 168 MHz from an 8 MHz crystal (as on
 * ST's STM32F4DISCOVERY). Register addresses and bits are those of ST's
 * RM0090 reference manual; docs/bringup-stm32f4.md explains the choices.
 *
 *   clocks   HSE 8 MHz -> PLL (M 8, N 336, P 2, Q 7): SYSCLK 168 MHz, USB 48 MHz;
 *            AHB 168 MHz, APB1 42 MHz (/4, its maximum), APB2 84 MHz (/2);
 *            flash 5 wait states (RM0090 table 10, 2.7-3.6 V)
 *   robot    USART1 on APB2 (84 MHz): TX PA9, RX PA10, AF7, interrupt 37
 *   laser    USART2 on APB1 (42 MHz): TX PA2, RX PA3, AF7, interrupt 38
 *   console  USART3 on APB1 (42 MHz): TX PB10, AF7, 115200 baud
 *   cycles   DWT CYCCNT at 168 MHz
 * USART1 and USART6 are clocked by APB2, USART2, USART3, UART4 and UART5 by
 * APB1: each port's divisor uses its own bus clock. */
#include <stddef.h>
#include <stdint.h>

#include "../board.h"
#include "rsm/status.h"

#define HSE_HZ 8000000u
#define CORE_HZ 168000000u
#define APB1_HZ 42000000u
#define APB2_HZ 84000000u
#define CONSOLE_BAUD 115200u

#define REG(addr) (*(volatile uint32_t *)(addr))

/* RCC (RM0090 section 7.3) */
#define RCC_CR REG(0x40023800u)
#define RCC_PLLCFGR REG(0x40023804u)
#define RCC_CFGR REG(0x40023808u)
#define RCC_AHB1ENR REG(0x40023830u)
#define RCC_APB1ENR REG(0x40023840u)
#define RCC_APB2ENR REG(0x40023844u)
#define RCC_CR_HSEON (1u << 16)
#define RCC_CR_HSERDY (1u << 17)
#define RCC_CR_PLLON (1u << 24)
#define RCC_CR_PLLRDY (1u << 25)
#define RCC_PLLCFGR_SRC_HSE (1u << 22)
#define RCC_CFGR_SW_PLL 2u
#define RCC_CFGR_SWS_MASK (3u << 2)
#define RCC_CFGR_SWS_PLL (2u << 2)
#define RCC_CFGR_PPRE1_DIV4 (5u << 10)
#define RCC_CFGR_PPRE2_DIV2 (4u << 13)
#define RCC_AHB1ENR_GPIOA (1u << 0)
#define RCC_AHB1ENR_GPIOB (1u << 1)
#define RCC_AHB1ENR_CCMDATARAM (1u << 20)
#define RCC_APB1ENR_USART2 (1u << 17)
#define RCC_APB1ENR_USART3 (1u << 18)
#define RCC_APB1ENR_PWR (1u << 28)
#define RCC_APB2ENR_USART1 (1u << 4)

/* Flash interface (RM0090 section 3.9) and power control (5.4) */
#define FLASH_ACR REG(0x40023C00u)
#define FLASH_ACR_5WS 5u
#define FLASH_ACR_PRFTEN (1u << 8)
#define FLASH_ACR_ICEN (1u << 9)
#define FLASH_ACR_DCEN (1u << 10)
#define PWR_CR REG(0x40007000u)
#define PWR_CR_VOS (1u << 14) /* scale 1: needed for 168 MHz */

/* GPIO (RM0090 section 8.4) */
#define GPIOA 0x40020000u
#define GPIOB 0x40020400u
#define GPIO_MODER(port) REG((port) + 0x00u)
#define GPIO_PUPDR(port) REG((port) + 0x0Cu)
#define GPIO_AFR(port, pin) REG((port) + ((pin) < 8u ? 0x20u : 0x24u))
#define AF_USART 7u

/* USART (RM0090 section 30.6) */
typedef struct usart_regs {
    volatile uint32_t sr;  /* RXNE bit 5, TC bit 6, TXE bit 7 */
    volatile uint32_t dr;
    volatile uint32_t brr; /* with OVER8 = 0: bus clock / baud, rounded */
    volatile uint32_t cr1; /* RE bit 2, TE bit 3, RXNEIE bit 5, UE bit 13 */
} usart_regs_t;

#define USART1 ((usart_regs_t *)0x40011000u)
#define USART2 ((usart_regs_t *)0x40004400u)
#define USART3 ((usart_regs_t *)0x40004800u)
#define SR_RXNE (1u << 5)
#define SR_TC (1u << 6)
#define SR_TXE (1u << 7)
#define CR1_RE (1u << 2)
#define CR1_TE (1u << 3)
#define CR1_RXNEIE (1u << 5)
#define CR1_UE (1u << 13)
#define TX_SPIN_LIMIT 100000u

/* Cortex-M4 core (ARMv7-M ARM: SysTick B3.3, NVIC B3.4, DWT C1.8, DEMCR C1.6) */
#define SYST_CSR REG(0xE000E010u)
#define SYST_RVR REG(0xE000E014u)
#define SYST_CVR REG(0xE000E018u)
#define NVIC_ISER1 REG(0xE000E104u)
#define DEMCR REG(0xE000EDFCu)
#define DEMCR_TRCENA (1u << 24)
#define DWT_CTRL REG(0xE0001000u)
#define DWT_CYCCNT REG(0xE0001004u)
#define IRQ_USART1 37u
#define IRQ_USART2 38u

const char rsm_board_name[] = "stm32f407";

uint32_t rsm_board_core_hz(void)
{
    return CORE_HZ;
}

/* Each port with the clock of its own bus. */
static uint32_t usart_clock_hz(const usart_regs_t *u)
{
    return u == USART1 ? APB2_HZ : APB1_HZ;
}

static void pin_af(uint32_t port, uint32_t pin, int pull_up)
{
    GPIO_MODER(port) = (GPIO_MODER(port) & ~(3u << (2u * pin))) | (2u << (2u * pin));
    GPIO_AFR(port, pin) = (GPIO_AFR(port, pin) & ~(0xFu << (4u * (pin & 7u)))) | (AF_USART << (4u * (pin & 7u)));
    if (pull_up) { /* an idle line stays high when the cable is out */
        GPIO_PUPDR(port) = (GPIO_PUPDR(port) & ~(3u << (2u * pin))) | (1u << (2u * pin));
    }
}

static void clocks_init(void)
{
    RCC_APB1ENR |= RCC_APB1ENR_PWR;
    PWR_CR |= PWR_CR_VOS;
    RCC_CR |= RCC_CR_HSEON;
    while ((RCC_CR & RCC_CR_HSERDY) == 0u) {
    }
    /* VCO in = 8 MHz / M 8 = 1 MHz; VCO = 336 MHz; SYSCLK = /P 2; USB = /Q 7. */
    RCC_PLLCFGR = 8u | (336u << 6) | (0u << 16) | RCC_PLLCFGR_SRC_HSE | (7u << 24);
    RCC_CR |= RCC_CR_PLLON;
    while ((RCC_CR & RCC_CR_PLLRDY) == 0u) {
    }
    /* Wait states before the faster clock, never after. */
    FLASH_ACR = FLASH_ACR_5WS | FLASH_ACR_PRFTEN | FLASH_ACR_ICEN | FLASH_ACR_DCEN;
    RCC_CFGR = RCC_CFGR_PPRE1_DIV4 | RCC_CFGR_PPRE2_DIV2 | RCC_CFGR_SW_PLL;
    while ((RCC_CFGR & RCC_CFGR_SWS_MASK) != RCC_CFGR_SWS_PLL) {
    }
}

void rsm_board_init(void)
{
    clocks_init();
    RCC_AHB1ENR |= RCC_AHB1ENR_GPIOA | RCC_AHB1ENR_GPIOB | RCC_AHB1ENR_CCMDATARAM;
    RCC_APB1ENR |= RCC_APB1ENR_USART2 | RCC_APB1ENR_USART3;
    RCC_APB2ENR |= RCC_APB2ENR_USART1;
    pin_af(GPIOA, 9u, 0);  /* USART1 TX */
    pin_af(GPIOA, 10u, 1); /* USART1 RX */
    pin_af(GPIOA, 2u, 0);  /* USART2 TX */
    pin_af(GPIOA, 3u, 1);  /* USART2 RX */
    pin_af(GPIOB, 10u, 0); /* USART3 TX: console */
    USART3->brr = (APB1_HZ + CONSOLE_BAUD / 2u) / CONSOLE_BAUD;
    USART3->cr1 = CR1_UE | CR1_TE;
    DEMCR |= DEMCR_TRCENA;
    DWT_CYCCNT = 0u;
    DWT_CTRL |= 1u; /* CYCCNTENA */
}

void rsm_board_console_write(const char *s, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        while ((USART3->sr & SR_TXE) == 0u) {
        }
        USART3->dr = (uint8_t)s[i];
    }
}

uint32_t rsm_board_cycles(void)
{
    return DWT_CYCCNT;
}

uint32_t rsm_board_cycles_hz(void)
{
    return CORE_HZ;
}

void *rsm_board_port_hw(rsm_board_port_t port)
{
    return port == RSM_BOARD_PORT_ROBOT ? (void *)USART1 : (void *)USART2;
}

int rsm_board_uart_tx_byte(void *hw, uint8_t byte)
{
    usart_regs_t *u = (usart_regs_t *)hw;
    uint32_t spins = TX_SPIN_LIMIT;
    while ((u->sr & SR_TXE) == 0u) {
        if (--spins == 0u) {
            return RSM_ERR_TIMEOUT;
        }
    }
    u->dr = byte;
    return RSM_OK;
}

int rsm_board_uart_set_baud(void *hw, uint32_t baud)
{
    usart_regs_t *u = (usart_regs_t *)hw;
    uint32_t div;
    uint32_t spins = TX_SPIN_LIMIT;
    if (baud == 0u) {
        return RSM_ERR_RANGE;
    }
    div = (usart_clock_hz(u) + baud / 2u) / baud;
    if (div < 16u || div > 0xFFFFu) {
        return RSM_ERR_RANGE;
    }
    /* The last byte written (e.g. the P3-DX's HOSTBAUD) leaves at the old
     * rate first (hal.h): wait for transmission complete. */
    while ((u->cr1 & CR1_UE) != 0u && (u->sr & SR_TC) == 0u && --spins != 0u) {
    }
    u->brr = div;
    u->cr1 = CR1_UE | CR1_TE | CR1_RE | CR1_RXNEIE;
    return RSM_OK;
}

int rsm_board_uart_rx_byte(void *hw, uint8_t *byte)
{
    usart_regs_t *u = (usart_regs_t *)hw;
    /* Reading SR then DR also clears an overrun (ORE). */
    if ((u->sr & SR_RXNE) == 0u) {
        return 0;
    }
    *byte = (uint8_t)(u->dr & 0xFFu);
    return 1;
}

void rsm_board_start_interrupts(void)
{
    SYST_RVR = CORE_HZ / 1000u - 1u;
    SYST_CVR = 0u;
    SYST_CSR = 7u; /* core clock, interrupt, enable */
    NVIC_ISER1 = (1u << (IRQ_USART1 - 32u)) | (1u << (IRQ_USART2 - 32u));
}

/* ---- vector table (RM0090 table 61) ------------------------------------------ */

static void usart1_isr(void)
{
    rsm_app_uart_isr(RSM_BOARD_PORT_ROBOT);
}

static void usart2_isr(void)
{
    rsm_app_uart_isr(RSM_BOARD_PORT_LASER);
}

#define DEFAULT RSM_BOARD_DEFAULT_VECTOR
#define DEFAULT8 DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT

/* 16 system exceptions, then the F407's 82 interrupts. */
__attribute__((section(".vectors"), used)) const rsm_vector_t rsm_vectors[16 + 82] = {
    RSM_BOARD_SYSTEM_VECTORS,
    DEFAULT8, DEFAULT8, DEFAULT8, DEFAULT8, /* interrupts 0..31 */
    DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, /* 32..36 */
    {.handler = usart1_isr},                     /* 37 */
    {.handler = usart2_isr},                     /* 38 */
    DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, DEFAULT, /* 39..47 */
    DEFAULT8, DEFAULT8, DEFAULT8, DEFAULT8,      /* 48..79 */
    DEFAULT, DEFAULT,                            /* 80, 81 */
};
