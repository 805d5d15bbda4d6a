/* The boards' shared start-up work (board.h): .data and .bss, a painted
 * stack whose high-water mark platform_phase() reports per phase (the
 * deepest painted word overwritten), and the program's run. The linker
 * scripts name the sections' bounds alike. */
#include "board.h"

#include "program.h"

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _sstack, _estack;
extern int program(void);

#define PAINT 0xC0A7C0A7u

void board_print_u32(uint32_t v) {
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

/* Paints the stack below what is in use now (16 words of margin). */
static void paint_below_sp(void) {
    uint32_t *sp = board_sp();
    for (uint32_t *p = &_sstack; p < sp - 16; p++) *p = PAINT;
}

void platform_phase(const char *name) {
    platform_print("board stack ");
    platform_print(name);
    platform_print(" bytes ");
    board_print_u32(stack_high_water());
    platform_print("\n");
    paint_below_sp();
}

int board_run(void) {
    for (uint32_t *s = &_sidata, *d = &_sdata; d < &_edata;) *d++ = *s++;
    for (uint32_t *d = &_sbss; d < &_ebss;) *d++ = 0;
    paint_below_sp();
    uint32_t before = stack_high_water();
    int status = program();
    platform_print("board stack before the program bytes ");
    board_print_u32(before);
    platform_print(" of ");
    board_print_u32((uint32_t)((uintptr_t)&_estack - (uintptr_t)&_sstack));
    platform_print("\n");
    return status;
}
