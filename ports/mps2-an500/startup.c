/* Reset and exception entry for the Cortex-M7 of QEMU's mps2-an500 (and of
 * any Cortex-M7 board with the same memory layout): the vector table, the
 * C run-time set-up (.data copied, .bss cleared, FPU on), then main() and a
 * semihosting exit with its result. A fault prints its name and exits
 * non-zero, so a crashing test fails instead of hanging the emulator. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

extern uint32_t __data_load__, __data_start__, __data_end__;
extern uint32_t __bss_start__, __bss_end__, __stack_top__;
extern int main(void);
extern void initialise_monitor_handles(void); /* newlib's rdimon */

void Reset_Handler(void);
void Fault_Handler(void);

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
    uint32_t *src = &__data_load__, *dst = &__data_start__;
    while (dst < &__data_end__)
        *dst++ = *src++;
    for (dst = &__bss_start__; dst < &__bss_end__;)
        *dst++ = 0;
    /* full access to CP10/CP11 (the FPU) before any floating point */
    SCB_CPACR |= 0xFu << 20;
    __asm volatile("dsb\n\tisb" ::: "memory");
    initialise_monitor_handles();
    exit(main());
}

void Fault_Handler(void)
{
    uint32_t ipsr;
    __asm volatile("mrs %0, ipsr" : "=r"(ipsr));
    printf("mps2-an500: fault (exception %lu)\n", (unsigned long)ipsr);
    exit(3);
}
