/* What a firmware image needs from its board: one interface, one
 * implementation per board under boards/<board>/ (board.c and link.ld), and
 * the common Cortex-M4F start-up in boards/startup_cm4.c.
 *
 *   mps2_an386  Arm MPS2 with the AN386 FPGA image (Cortex-M4F), as QEMU's
 *               mps2-an386 machine emulates it: the images ./tools/test boots.
 *   stm32f407   an STM32F407 at 168 MHz from an 8 MHz crystal
 *               (docs/bringup-stm32f4.md explains every choice).
 *
 * Two serial ports carry the devices (the P3-DX's and the LMS's) and a third
 * (or a debug probe) is the console. All functions are for the main loop
 * unless said otherwise; none allocates. */
#ifndef RSM_BOARD_H
#define RSM_BOARD_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The serial ports a firmware uses, by role. */
typedef enum rsm_board_port {
    RSM_BOARD_PORT_ROBOT = 0, /* the P3-DX */
    RSM_BOARD_PORT_LASER = 1, /* the LMS 2xx */
    RSM_BOARD_PORTS = 2
} rsm_board_port_t;

/* The board's name, for the banner. */
extern const char rsm_board_name[];

/* Core clock in Hz (what SysTick and DWT CYCCNT count). */
uint32_t rsm_board_core_hz(void);

/* Clocks, console, cycle counter; called first by main. The console is
 * usable after it returns. */
void rsm_board_init(void);

/* Writes n bytes to the console, waiting for each. */
void rsm_board_console_write(const char *s, size_t n);

/* A string, a decimal and an 8-digit hexadecimal number on the console
 * (boards/startup_cm4.c, for every board). */
void rsm_board_put_str(const char *s);
void rsm_board_put_dec(uint32_t v);
void rsm_board_put_hex(uint32_t v);

/* A free-running 32-bit up-counter of the core's work: CPU cycles where the
 * board has a cycle counter (DWT CYCCNT), else a timer (mps2: a 25 MHz
 * timer, which under QEMU's -icount counts executed instructions). */
uint32_t rsm_board_cycles(void);

/* Its rate in Hz. */
uint32_t rsm_board_cycles_hz(void);

/* Device ports: the hw pointer for rsm_uart_link_config_t, the functions it
 * takes, and the receive side for the port's interrupt. */
void *rsm_board_port_hw(rsm_board_port_t port);
int rsm_board_uart_tx_byte(void *hw, uint8_t byte);
int rsm_board_uart_set_baud(void *hw, uint32_t baud);
/* ISR context: the next received byte into *byte; 1 if there was one, else 0. */
int rsm_board_uart_rx_byte(void *hw, uint8_t *byte);

/* Starts the 1 kHz SysTick interrupt and the device ports' receive
 * interrupts (the handlers are the application's, below). */
void rsm_board_start_interrupts(void);

/* Sleeps until the next interrupt. This and rsm_board_exit have defaults
 * for real boards in boards/startup_cm4.c (weak: a board may define its own). */
void rsm_board_idle(void *hw);

/* Ends the run: on the emulated board QEMU exits with status 0 when status is
 * 0, else 1 (semihosting); on real hardware it stops in a loop where a
 * debugger will look. */
void rsm_board_exit(int status);

/* Interrupt handlers the application defines; the board's vector table
 * points at them (weak: an image that does not define them gets the default
 * handler, which reports an unexpected interrupt). */
void rsm_app_tick_isr(void);                 /* SysTick, 1 kHz */
void rsm_app_uart_isr(rsm_board_port_t port); /* a device port received */

/* ---- start-up (boards/startup_cm4.c) ---------------------------------------- */

/* The reset handler: enables the FPU, copies .data, zeroes .bss, paints the
 * unused stack, then calls main. */
void rsm_reset_handler(void);
/* Prints the fault and the stacked pc, then rsm_board_exit(1). */
void rsm_fault_handler(void);
void rsm_default_handler(void);

/* Bytes of stack used so far: the painted words overwritten since reset. */
size_t rsm_stack_used(void);
/* The stack's size from the linker script. */
size_t rsm_stack_size(void);

/* Sections from the linker script, for the start-up code and the reports. */
extern uint32_t rsm_ld_data_load[];
extern uint32_t rsm_ld_data_start[];
extern uint32_t rsm_ld_data_end[];
extern uint32_t rsm_ld_bss_start[];
extern uint32_t rsm_ld_bss_end[];
extern uint32_t rsm_ld_ccm_start[];
extern uint32_t rsm_ld_ccm_end[];
extern uint32_t rsm_ld_stack_bottom[];
extern uint32_t rsm_ld_stack_top[];

/* Puts a static object in core-coupled RAM where the board has some (an
 * STM32F4's 64 KiB CCM: no wait states, never contended by DMA, which the
 * application state never needs); in plain RAM elsewhere. Zeroed at reset. */
#define RSM_BOARD_CCM __attribute__((section(".ccm")))

/* One vector table entry: the initial stack pointer or a handler. */
typedef union rsm_vector {
    void (*handler)(void);
    void *stack;
} rsm_vector_t;

/* The 16 entries every ARMv7-M vector table starts with; the board's
 * interrupts follow. */
#define RSM_BOARD_DEFAULT_VECTOR {.handler = rsm_default_handler}
#define RSM_BOARD_SYSTEM_VECTORS                                                 \
    {.stack = rsm_ld_stack_top}, {.handler = rsm_reset_handler},                 \
    {.handler = rsm_fault_handler}, /* NMI */                                    \
    {.handler = rsm_fault_handler}, /* HardFault */                              \
    {.handler = rsm_fault_handler}, /* MemManage */                              \
    {.handler = rsm_fault_handler}, /* BusFault */                               \
    {.handler = rsm_fault_handler}, /* UsageFault */                             \
    RSM_BOARD_DEFAULT_VECTOR, RSM_BOARD_DEFAULT_VECTOR, RSM_BOARD_DEFAULT_VECTOR, \
    RSM_BOARD_DEFAULT_VECTOR, RSM_BOARD_DEFAULT_VECTOR, /* SVCall */             \
    RSM_BOARD_DEFAULT_VECTOR,                           /* DebugMonitor */       \
    RSM_BOARD_DEFAULT_VECTOR, RSM_BOARD_DEFAULT_VECTOR, /* PendSV */             \
    {.handler = rsm_app_tick_isr}                       /* SysTick */

#ifdef __cplusplus
}
#endif

#endif /* RSM_BOARD_H */
