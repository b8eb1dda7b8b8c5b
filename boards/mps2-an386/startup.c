/* Start-up of the MPS2-AN386 board (a Cortex-M4 under QEMU): the vector table at address 0 and
 * the reset handler, which hands over to newlib's _start (clears .bss, sets the stack and heap up
 * from the semihosting HEAPINFO call, runs the constructors, calls main and exits with its
 * status through semihosting). A fault ends the run with a message and a failing status instead
 * of QEMU's lockup, so a crashing test fails at once rather than at its timeout. */
#include <stdint.h>

void _start(void); /* newlib's C run-time entry (crt0) */
void board_reset(void);

/* Top of SSRAM2/3 (mps2-an386.ld): the stack pointer until _start sets its own. */
extern uint8_t __stack[];

void board_reset(void)
{
    _start();
    for (;;) {
    }
}

/* A semihosting call (ARM's semihosting specification: BKPT 0xAB on M-profile, operation in r0,
 * argument in r1, result in r0). */
static uint32_t semihost(uint32_t op, uintptr_t arg)
{
    register uint32_t r0 __asm__("r0") = op;
    register uintptr_t r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

#define SYS_WRITE0 0x04u                 /* write a NUL-terminated string to the console */
#define SYS_EXIT 0x18u                   /* report an exception to the debugger: stop */
#define ADP_STOPPED_RUNTIME_ERROR 0x20023u /* ...as a run-time error: QEMU exits with status 1 */

static void board_fault(void)
{
    (void)semihost(SYS_WRITE0, (uintptr_t)"mps2-an386: fault exception, stopping\n");
    (void)semihost(SYS_EXIT, ADP_STOPPED_RUNTIME_ERROR);
    for (;;) {
    }
}

/* ARMv7-M vector table (ARMv7-M Architecture Reference Manual, B1.5.3): the initial SP, then the
 * reset, NMI, HardFault, MemManage, BusFault and UsageFault handlers. Nothing here enables an
 * interrupt, so the table stops there. */
typedef struct vector_table {
    uint8_t *initial_sp;
    void (*handler[6])(void);
} vector_table;

__attribute__((section(".vectors"), used)) static const vector_table vectors = {
    __stack,
    {board_reset, board_fault, board_fault, board_fault, board_fault, board_fault},
};
