/* What the embedded test program needs from its platform: a way to print. */
#ifndef CORAY_EMBEDDED_PROGRAM_H
#define CORAY_EMBEDDED_PROGRAM_H

/* Prints a NUL-terminated string (semihosting on the board, stdout on the host). */
void platform_print(const char *s);

/* Runs every check; 0 when all passed. */
int program(void);

#endif
