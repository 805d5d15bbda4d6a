/* RV32IMAFC start-up for QEMU's virt machine (the project's own): _start
 * sets the stack, turns the FPU on (mstatus.FS) and a trap vector, then
 * reset() runs the program (board.c: .data, .bss, the painted stack);
 * semihosting prints and gives the exit status; the instruction counter
 * is minstret, which QEMU's -icount makes exact. */
#include <stdint.h>

#include "board.h"
#include "program.h"

#define SYS_WRITE0 0x04
#define SYS_EXIT 0x18
#define ADP_STOPPED_APPLICATION_EXIT 0x20026
#define ADP_STOPPED_RUN_TIME_ERROR 0x20023

/* The semihosting call is the three uncompressed instructions QEMU looks
   for (slli, ebreak, srai) on one page: a0 the operation, a1 its
   argument, the answer in a0. */
int semihost(int op, const void *arg);
__asm__(".section .text.start, \"ax\", @progbits\n"
        ".globl _start\n"
        "_start:\n"
        "    la sp, _estack\n"
        "    li t0, 0x2000\n" /* mstatus.FS = initial: F instructions allowed */
        "    csrs mstatus, t0\n"
        "    la t0, trap_entry\n"
        "    csrw mtvec, t0\n"
        "    call reset\n"
        "1:  j 1b\n"
        "    .balign 4\n"
        "trap_entry:\n"
        "    la sp, _estack\n"
        "    call trap\n"
        "    .balign 16\n"
        "    .option push\n"
        "    .option norvc\n"
        ".globl semihost\n"
        "semihost:\n"
        "    slli x0, x0, 0x1f\n"
        "    ebreak\n"
        "    srai x0, x0, 7\n"
        "    ret\n"
        "    .option pop\n");

void platform_print(const char *s) { semihost(SYS_WRITE0, s); }

uint64_t platform_instructions(void) {
    uint32_t hi, lo, again;
    do {
        __asm__ volatile("csrr %0, minstreth" : "=r"(hi));
        __asm__ volatile("csrr %0, minstret" : "=r"(lo));
        __asm__ volatile("csrr %0, minstreth" : "=r"(again));
    } while (hi != again);
    return (uint64_t)hi << 32 | lo;
}

uint32_t *board_sp(void) {
    uint32_t *sp;
    __asm__ volatile("mv %0, sp" : "=r"(sp));
    return sp;
}

__attribute__((noreturn)) static void stop(int ok) {
    semihost(SYS_EXIT, (const void *)(uintptr_t)(ok ? ADP_STOPPED_APPLICATION_EXIT
                                                     : ADP_STOPPED_RUN_TIME_ERROR));
    for (;;) {
    }
}

__attribute__((noreturn, used)) void reset(void) {
    int status = board_run();
    stop(status == 0);
}

/* Any exception: an illegal instruction, a misaligned or faulting access. */
__attribute__((noreturn, used)) void trap(void) {
    uint32_t cause;
    __asm__ volatile("csrr %0, mcause" : "=r"(cause));
    platform_print("embedded: FAILED (trap, mcause ");
    board_print_u32(cause);
    platform_print(")\n");
    stop(0);
}

/* The bare library's panic handler ends in abort() (it should never run:
   every entry point answers with a status). */
__attribute__((noreturn)) void abort(void) {
    platform_print("embedded: FAILED (abort)\n");
    stop(0);
}
