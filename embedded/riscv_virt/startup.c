/* RV32IMAFC start-up for QEMU's virt machine (the project's own): _start
 * sets the stack, turns the FPU on (mstatus.FS) and a trap vector, then
 * reset() copies .data, zeroes .bss, paints the stack and runs the
 * program; semihosting prints and gives the exit status; the
 * instruction counter is minstret, which QEMU's -icount makes exact.
 * After the program it reports the stack's high-water mark, as the
 * Cortex-M4's start-up does. */
#include <stdint.h>

#include "program.h"

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _sstack, _estack;

#define PAINT 0xC0A7C0A7u
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

static void print_u32(uint32_t v) {
    char buf[12];
    int i = 11;
    buf[i] = 0;
    do {
        buf[--i] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    platform_print(buf + i);
}

static uint32_t stack_high_water(void) {
    uint32_t *p = &_sstack;
    while (p < &_estack && *p == PAINT) p++;
    return (uint32_t)((uintptr_t)&_estack - (uintptr_t)p);
}

static void paint_below_sp(void) {
    uint32_t *sp;
    __asm__ volatile("mv %0, sp" : "=r"(sp));
    for (uint32_t *p = &_sstack; p < sp - 16; p++) *p = PAINT;
}

void platform_phase(const char *name) {
    platform_print("board stack ");
    platform_print(name);
    platform_print(" bytes ");
    print_u32(stack_high_water());
    platform_print("\n");
    paint_below_sp();
}

__attribute__((noreturn)) static void stop(int ok) {
    semihost(SYS_EXIT, (const void *)(uintptr_t)(ok ? ADP_STOPPED_APPLICATION_EXIT
                                                     : ADP_STOPPED_RUN_TIME_ERROR));
    for (;;) {
    }
}

__attribute__((noreturn, used)) void reset(void) {
    for (uint32_t *s = &_sidata, *d = &_sdata; d < &_edata;) *d++ = *s++;
    for (uint32_t *d = &_sbss; d < &_ebss;) *d++ = 0;
    paint_below_sp();
    uint32_t before = stack_high_water();
    int status = program();
    platform_print("board stack before the program bytes ");
    print_u32(before);
    platform_print(" of ");
    print_u32((uint32_t)((uintptr_t)&_estack - (uintptr_t)&_sstack));
    platform_print("\n");
    stop(status == 0);
}

/* Any exception: an illegal instruction, a misaligned or faulting access. */
__attribute__((noreturn, used)) void trap(void) {
    uint32_t cause;
    __asm__ volatile("csrr %0, mcause" : "=r"(cause));
    platform_print("embedded: FAILED (trap, mcause ");
    print_u32(cause);
    platform_print(")\n");
    stop(0);
}

/* The bare library's panic handler ends in abort() (it should never run:
   every entry point answers with a status). */
__attribute__((noreturn)) void abort(void) {
    platform_print("embedded: FAILED (abort)\n");
    stop(0);
}
