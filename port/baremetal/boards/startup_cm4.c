/* Start-up code common to every Cortex-M board: what runs between reset and
 * main, the fault report and the stack measurement. Written for the M4F; on
 * a core without FPU (soft float: __ARM_FP undefined) there is no FPU to
 * enable, and on ARMv6-M (Cortex-M0+) the fault handler keeps to its
 * instruction set. The vector table itself
 * is the board's (its device interrupts differ), in boards/<board>/board.c. */
#include <stddef.h>
#include <stdint.h>

#include "board.h"
#include "fmt.h"

#define PAINT 0x5AA5C33Cu /* unlikely as live stack data */

/* Coprocessor access control (ARMv7-M architecture reference manual, B3.2.20):
 * CP10 and CP11, the FPU, full access. */
#define CPACR (*(volatile uint32_t *)0xE000ED88u)
#define CPACR_CP10_CP11_FULL (0xFu << 20)

int main(void);

/* Copies and zeroes word by word. Kept apart from the reset handler and never
 * inlined, so that nothing of it runs before the FPU is on. */
static void __attribute__((noinline)) init_memory(void)
{
    uint32_t *dst = rsm_ld_data_start;
    const uint32_t *src = rsm_ld_data_load;
    while (dst < rsm_ld_data_end) {
        *dst++ = *src++;
    }
    for (dst = rsm_ld_bss_start; dst < rsm_ld_bss_end; ++dst) {
        *dst = 0u;
    }
    /* Statics placed in core-coupled RAM are zero-initialised like .bss. */
    for (dst = rsm_ld_ccm_start; dst < rsm_ld_ccm_end; ++dst) {
        *dst = 0u;
    }
}

/* Paints the stack from its bottom to 64 bytes below the current frame. */
static void __attribute__((noinline)) paint_stack(void)
{
    uint32_t sp;
    uint32_t *p = rsm_ld_stack_bottom;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    while ((uint32_t)(uintptr_t)p + 64u < sp) {
        *p++ = PAINT;
    }
}

void rsm_reset_handler(void)
{
#if defined(__ARM_FP)
    /* The FPU first: any float instruction before this is a UsageFault, and
     * the compiler may use FPU registers anywhere in C code. */
    CPACR |= CPACR_CP10_CP11_FULL;
    __asm__ volatile("dsb\n\tisb" ::: "memory");
#endif
    init_memory();
    paint_stack();
    (void)main();
    rsm_board_exit(0);
}

size_t rsm_stack_used(void)
{
    const uint32_t *p = rsm_ld_stack_bottom;
    while (p < rsm_ld_stack_top && *p == PAINT) {
        ++p;
    }
    return (size_t)(rsm_ld_stack_top - p) * sizeof(uint32_t);
}

size_t rsm_stack_size(void)
{
    return (size_t)(rsm_ld_stack_top - rsm_ld_stack_bottom) * sizeof(uint32_t);
}

void rsm_board_put_str(const char *s)
{
    size_t n = 0;
    while (s[n] != '\0') {
        ++n;
    }
    rsm_board_console_write(s, n);
}

void rsm_board_put_dec(uint32_t v)
{
    char buf[RSM_FMT_DEC_MAX];
    const size_t first = rsm_fmt_dec(buf, v);
    rsm_board_console_write(buf + first, sizeof buf - first);
}

void rsm_board_put_hex(uint32_t v)
{
    char buf[8];
    rsm_fmt_hex(buf, v);
    rsm_board_console_write(buf, sizeof buf);
}

/* Called with the stacked frame: r0 r1 r2 r3 r12 lr pc xpsr. */
void rsm_fault_report(const uint32_t *frame);
void rsm_fault_report(const uint32_t *frame)
{
    rsm_board_put_str("\nFAULT: pc ");
    rsm_board_put_hex(frame[6]);
    rsm_board_put_str(" lr ");
    rsm_board_put_hex(frame[5]);
#if !defined(__ARM_ARCH_6M__)
    /* HFSR and CFSR say why (ARMv7-M ARM, B3.2.15 and B3.2.16); ARMv6-M has
     * neither. */
    {
        const uint32_t cfsr = *(volatile const uint32_t *)0xE000ED28u;
        const uint32_t hfsr = *(volatile const uint32_t *)0xE000ED2Cu;
        rsm_board_put_str(" cfsr ");
        rsm_board_put_hex(cfsr);
        rsm_board_put_str(" hfsr ");
        rsm_board_put_hex(hfsr);
    }
#endif
    rsm_board_put_str("\n");
    rsm_board_exit(1);
}

/* Finds the frame on whichever stack was in use (EXC_RETURN bit 2). */
void __attribute__((naked)) rsm_fault_handler(void)
{
#if defined(__ARM_ARCH_6M__)
    /* No IT blocks, no test of lr against an immediate, a short b range. */
    __asm__ volatile("movs r0, #4\n\t"
                     "mov r1, lr\n\t"
                     "tst r0, r1\n\t"
                     "bne 1f\n\t"
                     "mrs r0, msp\n\t"
                     "b 2f\n"
                     "1:\n\t"
                     "mrs r0, psp\n"
                     "2:\n\t"
                     "ldr r1, =rsm_fault_report\n\t"
                     "bx r1\n");
#else
    __asm__ volatile("tst lr, #4\n\t"
                     "ite eq\n\t"
                     "mrseq r0, msp\n\t"
                     "mrsne r0, psp\n\t"
                     "b rsm_fault_report\n");
#endif
}

void rsm_default_handler(void)
{
    rsm_board_put_str("\nFAULT: unexpected interrupt\n");
    rsm_board_exit(1);
}

/* A real board's idle and end of run (the emulated one ends the run
 * through semihosting instead): sleep until the next interrupt; stop in a
 * loop where a debugger will look. */
void __attribute__((weak)) rsm_board_idle(void *hw)
{
    (void)hw;
    __asm__ volatile("wfi");
}

void __attribute__((weak)) rsm_board_exit(int status)
{
    (void)status;
    for (;;) {
        __asm__ volatile("wfi"); /* a debugger finds the run ended here */
    }
}

/* The application's handlers, when it has none. */
void __attribute__((weak)) rsm_app_tick_isr(void)
{
    rsm_default_handler();
}

void __attribute__((weak)) rsm_app_uart_isr(rsm_board_port_t port)
{
    (void)port;
    rsm_default_handler();
}
