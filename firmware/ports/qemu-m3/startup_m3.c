/*
 * startup_m3.c -- vector table and reset handler of the qemu-m3 port
 * (Cortex-M3, no FPU).  Reset (ARMv7-M ARM B1.5.5): SP from vector 0, PC
 * from vector 1.  Reset_Handler sets SP, copies .data from its load
 * address, zeroes .bss and calls main().  No FPU to enable: the image is
 * built with -mfloat-abi=soft (float arithmetic, if any, is libgcc's).
 */
#include <stdint.h>

#include "m3.h"
#include "port.h"

int main(void);
void Reset_Handler(void);
void Default_Handler(void);

/* The first instruction sets SP; only basic asm in a naked function (GCC manual). */
__attribute__((naked, noreturn)) void Reset_Handler(void)
{
    __asm__ volatile("ldr sp, =_estack\n\t"
                     "b m3_reset\n\t"
                     ".ltorg");
}

__attribute__((noreturn)) void m3_reset(void)
{
    volatile uint32_t *d = &_sdata;
    const uint32_t *s = &_sidata;
    volatile uint32_t *p;
    if (s != &_sdata) {
        while (d < &_edata) {
            *d = *s;
            ++d;
            ++s;
        }
    }
    for (p = &_sbss; p < &_ebss; ++p) {
        *p = 0u;
    }
    M3_DSB();
    M3_ISB();
    (void)main();
    port_exit(2u);
    for (;;) {
    }
}

void Default_Handler(void)
{
    uint32_t ipsr;
    __asm__ volatile("mrs %0, ipsr" : "=r"(ipsr));
    m3_fault(ipsr & 0x1FFu);
}

/* Vector table: 16 system entries (ARMv7-M ARM B1.5.3) + 16 IRQs (unused). */
__attribute__((section(".isr_vector"), used))
const uintptr_t m3_vectors[32] = {
    (uintptr_t)&_estack,
    (uintptr_t)Reset_Handler,
    (uintptr_t)Default_Handler, /* NMI */
    (uintptr_t)Default_Handler, /* HardFault */
    (uintptr_t)Default_Handler, /* MemManage */
    (uintptr_t)Default_Handler, /* BusFault */
    (uintptr_t)Default_Handler, /* UsageFault */
    0u, 0u, 0u, 0u,
    (uintptr_t)Default_Handler, /* SVCall */
    (uintptr_t)Default_Handler, /* DebugMonitor */
    0u,
    (uintptr_t)Default_Handler, /* PendSV */
    (uintptr_t)Default_Handler, /* SysTick */
    (uintptr_t)Default_Handler, (uintptr_t)Default_Handler, (uintptr_t)Default_Handler,
    (uintptr_t)Default_Handler, (uintptr_t)Default_Handler, (uintptr_t)Default_Handler,
    (uintptr_t)Default_Handler, (uintptr_t)Default_Handler, (uintptr_t)Default_Handler,
    (uintptr_t)Default_Handler, (uintptr_t)Default_Handler, (uintptr_t)Default_Handler,
    (uintptr_t)Default_Handler, (uintptr_t)Default_Handler, (uintptr_t)Default_Handler,
    (uintptr_t)Default_Handler,
};
