/* Start-up for the C firmware on QEMU's mps2-an386 (Cortex-M4F): the vector
 * table, RAM set-up, the FPU, semihosting I/O (newlib's librdimon), the
 * command line, then `firmware_main`. Built with Debian's arm-none-eabi-gcc
 * and newlib (c/metal/run).
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

extern uint32_t __data_load, __data_start, __data_end, __bss_start, __bss_end, __stack_top;
extern void initialise_monitor_handles(void);
int firmware_main(int argc, char **argv);
void reset(void);

static void halt(void) {
    for (;;) {
    }
}

/* The initial stack pointer, then the handlers: reset, and every fault stops. */
__attribute__((section(".vectors"), used)) static void (*const vectors[16])(void) = {
    (void (*)(void))(&__stack_top), reset, halt, halt, halt, halt, halt, 0, 0, 0, 0, halt, halt, 0, halt, halt,
};

/* A semihosting call (ARM's `BKPT 0xAB`). */
static int semihost(int op, void *arg) {
    register int r0 __asm__("r0") = op;
    register void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

static char cmdline[256];
static char *args[8];

void reset(void) {
    /* The FPU: full access for CP10 and CP11 (the Rust library is hard-float). */
    *(volatile uint32_t *)0xE000ED88 |= 0xFu << 20;
    __asm__ volatile("dsb\n isb");
    memcpy(&__data_start, &__data_load, (size_t)((char *)&__data_end - (char *)&__data_start));
    memset(&__bss_start, 0, (size_t)((char *)&__bss_end - (char *)&__bss_start));
    initialise_monitor_handles();
    /* SYS_GET_CMDLINE (0x15): the command line QEMU was given, split at spaces. */
    struct { char *buf; int len; } block = {cmdline, (int)sizeof cmdline - 1};
    int argc = 0;
    if (semihost(0x15, &block) == 0) {
        for (char *p = strtok(cmdline, " "); p && argc < 8; p = strtok(NULL, " ")) args[argc++] = p;
    }
    exit(firmware_main(argc, args));
}
