/* The embedded test program on the host: stdout for printing. */
#include <stdio.h>

#include "program.h"

void platform_print(const char *s) { fputs(s, stdout); }

void platform_phase(const char *name) { (void)name; }

uint64_t platform_instructions(void) { return UINT64_MAX; }

int main(void) { return program(); }
