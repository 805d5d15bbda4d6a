/* Cortex-M4F start-up for QEMU's mps2-an386 (the project's own; no vendor
 * files): the vector table, a reset handler that enables the FPU and runs
 * the program (board.c: .data, .bss, the painted stack), semihosting for
 * printing and for the exit status; the instruction counter reads the
 * FPGA's 25 MHz counter, which QEMU's -icount turns into instructions. */
#include <stdint.h>

#include "board.h"
#include "program.h"

extern uint32_t _estack;

#define SYS_WRITE0 0x04
#define SYS_EXIT 0x18
#define ADP_STOPPED_APPLICATION_EXIT 0x20026
#define ADP_STOPPED_RUN_TIME_ERROR 0x20023

static int semihost(int op, const void *arg) {
    register int r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void platform_print(const char *s) { semihost(SYS_WRITE0, s); }

/* The FPGAIO block's COUNTER: 32 bits at 25 MHz (40 ns a tick) of QEMU's
   virtual clock. scripts/embedded.sh runs QEMU with -icount shift=6, one
   instruction per 64 ns, so 8 ticks are 5 instructions. Read more often
   than every 2^32 ticks (2.7 billion instructions) to see every wrap. */
#define FPGAIO_COUNTER (*(volatile uint32_t *)0x40028018u)
#define ICOUNT_NS_PER_INSTRUCTION 64u
#define COUNTER_NS_PER_TICK 40u

uint64_t platform_instructions(void) {
    static uint32_t last;
    static uint64_t ticks;
    uint32_t now = FPGAIO_COUNTER;
    ticks += (uint32_t)(now - last);
    last = now;
    return ticks * COUNTER_NS_PER_TICK / ICOUNT_NS_PER_INSTRUCTION;
}

uint32_t *board_sp(void) {
    uint32_t *sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    return sp;
}

__attribute__((noreturn)) void Reset_Handler(void) {
    /* CP10 and CP11 full access: the FPU, before any float instruction. */
    *(volatile uint32_t *)0xE000ED88u |= 0xFu << 20;
    __asm__ volatile("dsb\n isb");
    int status = board_run();
    semihost(SYS_EXIT, (const void *)(uintptr_t)(status == 0 ? ADP_STOPPED_APPLICATION_EXIT
                                                             : ADP_STOPPED_RUN_TIME_ERROR));
    for (;;) {
    }
}

static void Fault_Handler(void) {
    platform_print("embedded: FAILED (fault)\n");
    semihost(SYS_EXIT, (const void *)(uintptr_t)ADP_STOPPED_RUN_TIME_ERROR);
    for (;;) {
    }
}

/* The bare library's panic handler ends in abort() (it should never run:
   every entry point answers with a status). */
__attribute__((noreturn)) void abort(void) {
    platform_print("embedded: FAILED (abort)\n");
    semihost(SYS_EXIT, (const void *)(uintptr_t)ADP_STOPPED_RUN_TIME_ERROR);
    for (;;) {
    }
}

/* Initial stack pointer, reset, NMI, hard fault, memory management, bus
   and usage faults; the rest of the table is never taken here. */
__attribute__((section(".vectors"), used)) static const void *const vectors[16] = {
    &_estack,      (void *)Reset_Handler, (void *)Fault_Handler, (void *)Fault_Handler,
    (void *)Fault_Handler, (void *)Fault_Handler, (void *)Fault_Handler,
};
