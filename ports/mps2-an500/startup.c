/* Reset and exception entry for the Cortex-M7 of QEMU's mps2-an500 (and of
 * any Cortex-M7 board with the same memory layout): the vector table, the
 * C run-time set-up (.data copied, .bss cleared, FPU on), then main() and a
 * semihosting exit with its result. A fault prints its name and exits
 * non-zero, so a crashing test fails instead of hanging the emulator. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

extern uint32_t __data_load__, __data_start__, __data_end__;
extern uint32_t __bss_start__, __bss_end__, __stack_top__, __stack_bottom__;
extern int main(void);
extern void initialise_monitor_handles(void); /* newlib's rdimon */

void Reset_Handler(void);
void Fault_Handler(void);
unsigned long mps2_stack_used(void);

/* Written over the stack at reset, so that the deepest the stack went can
 * be read off afterwards (mps2_stack_used). */
#define STACK_PAINT 0x5AA55AA5u

/* Cortex-M7 system control: coprocessor access control (CPACR). */
#define SCB_CPACR (*(volatile uint32_t *)0xE000ED88u)

__attribute__((section(".vectors"),
               used)) static void (*const vectors[16])(void) = {
    (void (*)(void))(&__stack_top__), /* initial stack pointer */
    Reset_Handler,
    Fault_Handler, /* NMI */
    Fault_Handler, /* HardFault */
    Fault_Handler, /* MemManage */
    Fault_Handler, /* BusFault */
    Fault_Handler, /* UsageFault */
    0,
    0,
    0,
    0,
    Fault_Handler, /* SVCall */
    Fault_Handler, /* DebugMonitor */
    0,
    Fault_Handler, /* PendSV */
    Fault_Handler, /* SysTick */
};

void Reset_Handler(void)
{
    uint32_t *src = &__data_load__, *dst = &__data_start__, *sp;
    while (dst < &__data_end__)
        *dst++ = *src++;
    for (dst = &__bss_start__; dst < &__bss_end__;)
        *dst++ = 0;
    /* paint the stack below this frame (64 words spare for it) */
    __asm volatile("mov %0, sp" : "=r"(sp));
    for (dst = &__stack_bottom__; dst < sp - 64;)
        *dst++ = STACK_PAINT;
    /* full access to CP10/CP11 (the FPU) before any floating point */
    SCB_CPACR |= 0xFu << 20;
    __asm volatile("dsb\n\tisb" ::: "memory");
    initialise_monitor_handles();
    exit(main());
}

/* Bytes of the stack ever written since reset: from its top down to the
 * lowest word no longer holding the paint. */
unsigned long mps2_stack_used(void)
{
    const uint32_t *w = &__stack_bottom__;
    while (w < &__stack_top__ && *w == STACK_PAINT)
        w++;
    return (unsigned long)((const char *)&__stack_top__ - (const char *)w);
}

void Fault_Handler(void)
{
    uint32_t ipsr;
    __asm volatile("mrs %0, ipsr" : "=r"(ipsr));
    printf("mps2-an500: fault (exception %lu)\n", (unsigned long)ipsr);
    exit(3);
}
