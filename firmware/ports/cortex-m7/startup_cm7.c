/*
 * startup_cm7.c -- vector table and reset handler shared by the Cortex-M7
 * ports (stm32h743, qemu-m7).  Reset (ARMv7-M ARM B1.5.5): SP from vector 0,
 * PC from vector 1.  Reset_Handler enables the FPU first (no float
 * instruction may run before CPACR grants CP10/CP11), copies .itcm_text,
 * .dtcm_rodata and .data from their load addresses, zeroes .bss and calls
 * main().
 */
#include <stdint.h>

#include "cm7.h"
#include "port.h"

int main(void);
void Reset_Handler(void);
void Default_Handler(void);

/* Copy words [dst, end) from src; nothing to do when loaded in place.
 * Volatile accesses: the loop must not become a memcpy call, since memcpy
 * itself may live in ITCM, which is not copied yet (stm32h743.ld). */
static void copy_words(const uint32_t *src, uint32_t *dst, const uint32_t *end)
{
    volatile uint32_t *d = dst;
    if (src == dst) {
        return;
    }
    while (d < end) {
        *d = *src;
        ++d;
        ++src;
    }
}

/* The first instruction sets SP (tests/firmware/test_port_layout.py reads it
 * back from the ELF); only basic asm in a naked function (GCC manual). */
__attribute__((naked, noreturn)) void Reset_Handler(void)
{
    __asm__ volatile("ldr sp, =_estack\n\t"
                     "b cm7_reset\n\t"
                     ".ltorg");
}

__attribute__((noreturn)) void cm7_reset(void)
{
    volatile uint32_t *p;
    cm7_fpu_enable();
    copy_words(&_siitcm, &_sitcm, &_eitcm);
    copy_words(&_sidtcm, &_sdtcm, &_edtcm);
    copy_words(&_sidata, &_sdata, &_edata);
    for (p = &_sbss; p < &_ebss; ++p) {
        *p = 0u;
    }
    CM7_DSB();
    CM7_ISB(); /* code copied to ITCM is visible to instruction fetch */
    (void)main();
    port_exit(2u);
    for (;;) {
    }
}

void Default_Handler(void)
{
    uint32_t ipsr;
    __asm__ volatile("mrs %0, ipsr" : "=r"(ipsr));
    cm7_fault(ipsr & 0x1FFu);
}

/* Vector table: 16 system entries (ARMv7-M ARM B1.5.3) + 16 IRQs (unused). */
__attribute__((section(".isr_vector"), used))
const uintptr_t cm7_vectors[32] = {
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
