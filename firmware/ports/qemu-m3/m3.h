/*
 * m3.h -- the few ARMv7-M core registers the qemu-m3 port uses (no vendor
 * SDK, no FPU).  Reference: Arm ARMv7-M Architecture Reference Manual
 * (DDI 0403E, "ARMv7-M ARM").  The Cortex-M3 has no floating-point unit:
 * the image is built with -mfloat-abi=soft, so no instruction of it touches
 * CP10/CP11 and nothing needs enabling at reset.
 */
#ifndef M3_H
#define M3_H

#include <stdint.h>

#define M3_REG(addr) (*(volatile uint32_t *)(uintptr_t)(addr))

/* System Control Block (ARMv7-M ARM B3.2.2, table B3-4) */
#define SCB_CPUID   M3_REG(0xE000ED00u) /* B3.2.3 PARTNO[15:4]: 0xC23 on a Cortex-M3 */

/* SysTick (ARMv7-M ARM B3.3, table B3-7) */
#define SYST_CSR    M3_REG(0xE000E010u) /* B3.3.3 control and status */
#define SYST_RVR    M3_REG(0xE000E014u) /* B3.3.4 reload value (24 bits) */
#define SYST_CVR    M3_REG(0xE000E018u) /* B3.3.5 current value, counts down */
#define SYST_CSR_ENABLE    (1u << 0)
#define SYST_CSR_CLKSOURCE (1u << 2)     /* 1: processor clock */

/* Barriers (ARMv7-M ARM A7.7.26 DSB, A7.7.33 ISB) */
#define M3_DSB() __asm__ volatile("dsb 0xF" ::: "memory")
#define M3_ISB() __asm__ volatile("isb 0xF" ::: "memory")

/* SysTick free-running over 24 bits from the processor clock (B3.3). */
static inline void m3_systick_free_run(void)
{
    SYST_CSR = 0u;
    SYST_RVR = 0x00FFFFFFu;
    SYST_CVR = 0u;
    SYST_CSR = SYST_CSR_CLKSOURCE | SYST_CSR_ENABLE;
}

/* Up-counting view of SysTick, modulo 2^24. */
static inline uint32_t m3_systick_up(void)
{
    return (0x00FFFFFFu - SYST_CVR) & 0x00FFFFFFu;
}

/* Linker-script symbols (qemu_m3.ld). */
extern uint32_t _estack;                      /* initial stack pointer */
extern uint32_t _sidata, _sdata, _edata;      /* .data: load, start, end */
extern uint32_t _sbss, _ebss;                 /* .bss */

/* Unhandled exception: the port reports and stops (board.c). */
void m3_fault(uint32_t vector);

/* Reset_Handler's C part, after SP is set (startup_m3.c). */
void m3_reset(void) __attribute__((noreturn));

#endif /* M3_H */
