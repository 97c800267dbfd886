/* Start-up for the Arm MPS2 boards that QEMU models (AN500: Cortex-M7, AN386: Cortex-M4): the
 * vector table, the FPU switched on, .data copied to RAM, then newlib's start (rdimon: its
 * semihosting crt0, which clears .bss and calls main). SysTick counts the virtual clock, which
 * under QEMU's -icount advances with every instruction executed (bench_ticks). */
#include <stdint.h>

extern void _start(void);
extern uint32_t __StackTop, __etext, __data_start__, __data_end__;
static volatile uint32_t overflows;

void reset_handler(void)
{
    /* CP10 and CP11 full access (CPACR) before any floating-point instruction */
    *(volatile uint32_t *)0xE000ED88 |= (0xFu << 20);
    __asm volatile("dsb\n isb");
    const uint32_t *from = &__etext;
    for (uint32_t *to = &__data_start__; to < &__data_end__;) {
        *to++ = *from++;
    }
    _start();
    for (;;) {
    }
}

void systick_handler(void)
{
    overflows++;
}

static void fault_handler(void)
{
    for (;;) {
    }
}

__attribute__((section(".vectors"), used)) const void *const vectors[16] = {
    &__StackTop, (const void *)reset_handler, (const void *)fault_handler,
    (const void *)fault_handler, (const void *)fault_handler, (const void *)fault_handler,
    (const void *)fault_handler, 0, 0, 0, 0, (const void *)fault_handler,
    (const void *)fault_handler, 0, (const void *)fault_handler, (const void *)systick_handler,
};

#define SYST ((volatile uint32_t *)0xE000E010) /* CSR, RVR, CVR */

void bench_ticks_start(void)
{
    SYST[1] = 0xFFFFFFu;
    SYST[2] = 0u;
    SYST[0] = 0x7u; /* processor clock, interrupt on wrap, enabled */
    while (SYST[2] == 0u) { /* until the first reload */
    }
}

uint64_t bench_ticks(void)
{
    uint32_t o1, v, o2;
    do {
        o1 = overflows;
        v = SYST[2];
        o2 = overflows;
    } while (o1 != o2);
    return ((uint64_t)o1 << 24) + (0xFFFFFFu - v);
}
