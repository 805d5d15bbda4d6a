/* What the embedded test program needs from its platform: a way to print,
   stack marks per phase and an instruction counter. */
#ifndef CORAY_EMBEDDED_PROGRAM_H
#define CORAY_EMBEDDED_PROGRAM_H

#include <stdint.h>

/* Prints a NUL-terminated string (semihosting on the board, stdout on the host). */
void platform_print(const char *s);

/* Marks the end of a phase: the board prints the deepest stack the phase
   used (a painted stack) and paints again; the host does nothing. */
void platform_phase(const char *name);

/* Instructions retired so far, where the platform counts them
   deterministically (QEMU's -icount on the boards); UINT64_MAX where it
   does not (the host), and the program then prints no count lines. */
uint64_t platform_instructions(void);

/* Runs every check; 0 when all passed. */
int program(void);

#endif
