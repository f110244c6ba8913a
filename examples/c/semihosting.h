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
#endif
