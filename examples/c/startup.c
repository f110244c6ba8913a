/*
 * Minimal Cortex-M4F start-up and ARM semihosting for QEMU's mps2-an386: a vector table, a
 * reset handler that copies .data, clears .bss and enables the FPU, and the three semihosting
 * calls the example needs (write a string, read the command line, exit with a code). No C
 * library: the example is freestanding; the Rust static library brings memcpy/memset.
 */
#include <stdint.h>

#include "semihosting.h"

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _stack_top;
int main(void);

static int semihost(int op, void *arg)
{
    register int r0 __asm__("r0") = op;
    register void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void sh_write(const char *s) { semihost(0x04 /* SYS_WRITE0 */, (void *)s); }

int sh_cmdline(char *buf, uint32_t len)
{
    uint32_t block[2] = {(uint32_t)buf, len};
    return semihost(0x15 /* SYS_GET_CMDLINE */, block);
}

void sh_exit(int code)
{
    uint32_t block[2] = {0x20026 /* ADP_Stopped_ApplicationExit */, (uint32_t)code};
    semihost(0x20 /* SYS_EXIT_EXTENDED */, block);
    semihost(0x18 /* SYS_EXIT */, (void *)(code == 0 ? 0x20026 : 0x20024));
    for (;;) {
    }
}

#define PAINT 0xCCCCCCCCu

/* Not inlined: its own frame lies below the caller's, and the paint stops below both. */
__attribute__((noinline)) void stack_paint(void)
{
    uint32_t *sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    for (volatile uint32_t *p = &_ebss; p < sp - 16; p++) {
        *p = PAINT;
    }
}

uint32_t stack_used(void)
{
    const volatile uint32_t *p = &_ebss;
    while (p < &_stack_top && *p == PAINT) {
        p++;
    }
    return (uint32_t)((uintptr_t)&_stack_top - (uintptr_t)p);
}

void reset_handler(void)
{
    uint32_t *src = &_sidata, *dst = &_sdata;
    while (dst < &_edata) {
        *dst++ = *src++;
    }
    for (dst = &_sbss; dst < &_ebss; dst++) {
        *dst = 0;
    }
    /* CPACR: full access to CP10 and CP11 (the FPU), before any floating-point instruction. */
    *(volatile uint32_t *)0xE000ED88 |= 0xFu << 20;
    __asm__ volatile("dsb\n\tisb" ::: "memory");
    stack_paint();
    sh_exit(main());
}

static void fault_handler(void)
{
    sh_write("fault (a trap: HardFault, or the Rust library's panic handler)\n");
    sh_exit(101);
}

__attribute__((section(".vectors"), used)) static void (*const vectors[16])(void) = {
    (void (*)(void))&_stack_top, /* initial stack pointer */
    reset_handler,
    fault_handler, /* NMI */
    fault_handler, /* HardFault */
    fault_handler, /* MemManage */
    fault_handler, /* BusFault */
    fault_handler, /* UsageFault */
};
