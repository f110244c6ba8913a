/* ARM semihosting under QEMU (-semihosting-config enable=on,target=native). */
#ifndef SEMIHOSTING_H
#define SEMIHOSTING_H
#include <stdint.h>
/* Writes a NUL-terminated string to the host's stdout. */
void sh_write(const char *s);
/* Copies the command line (qemu -append "...") into buf; 0 on success. */
int sh_cmdline(char *buf, uint32_t len);
/* Ends the run with an exit code for the shell. */
void sh_exit(int code) __attribute__((noreturn));
/* Paints the free stack (from the end of .bss to just below the caller's frame) with a pattern;
   the reset handler does it once before main. */
void stack_paint(void);
/* Bytes of stack used from its top (the reset's stack pointer) since the last paint: the
   high-water mark, the lowest word no longer holding the pattern. */
uint32_t stack_used(void);
#endif
