/* What both boards' start-up code shares (board.c): the painted stack
 * and the program's run. Each board gives its stack pointer and its
 * semihosting; board.c does the rest. */
#ifndef CORAY_EMBEDDED_BOARD_H
#define CORAY_EMBEDDED_BOARD_H

#include <stdint.h>

/* The stack pointer where it is called (each start-up's own asm). */
uint32_t *board_sp(void);

/* Copies .data, zeroes .bss, paints the stack, runs the program and
   prints the stack the start-up used before it; the program's status. */
int board_run(void);

/* Prints `v` in decimal. */
void board_print_u32(uint32_t v);

#endif
