/* What the embedded test program needs from its platform: a way to print. */
#ifndef CORAY_EMBEDDED_PROGRAM_H
#define CORAY_EMBEDDED_PROGRAM_H

/* Prints a NUL-terminated string (semihosting on the board, stdout on the host). */
void platform_print(const char *s);

/* Marks the end of a phase: the board prints the deepest stack the phase
   used (a painted stack) and paints again; the host does nothing. */
void platform_phase(const char *name);

/* Runs every check; 0 when all passed. */
int program(void);

#endif
