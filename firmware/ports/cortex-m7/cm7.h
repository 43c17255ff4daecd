/*
 * cm7.h -- the few Cortex-M7 core registers the ports use (no vendor SDK).
 * References: Arm ARMv7-M Architecture Reference Manual (DDI 0403E, "ARMv7-M
 * ARM") and the Cortex-M7 Technical Reference Manual (DDI 0489, "M7 TRM").
 */
#ifndef CM7_H
#define CM7_H

#include <stdint.h>

#define CM7_REG(addr) (*(volatile uint32_t *)(uintptr_t)(addr))

/* System Control Block (ARMv7-M ARM B3.2.2, table B3-4) */
#define SCB_VTOR    CM7_REG(0xE000ED08u) /* B3.2.5 vector table offset */
#define SCB_CCR     CM7_REG(0xE000ED14u) /* B3.2.8 configuration and control */
#define SCB_CCR_DC  (1u << 16)           /* data cache enable */
#define SCB_CCR_IC  (1u << 17)           /* instruction cache enable */
#define SCB_CCSIDR  CM7_REG(0xE000ED80u) /* B4.8.3 cache size ID */
#define SCB_CSSELR  CM7_REG(0xE000ED84u) /* B4.8.4 cache size selection */
#define SCB_CPACR   CM7_REG(0xE000ED88u) /* B3.2.20 coprocessor access control: CP10/CP11 bits 23:20 */
#define SCB_DEMCR   CM7_REG(0xE000EDFCu) /* C1.6.5 debug exception and monitor control */
#define SCB_DEMCR_TRCENA (1u << 24)
#define FPU_MVFR0   CM7_REG(0xE000EF40u) /* B4.6.5 media and VFP feature register 0 */
#define SCB_ICIALLU CM7_REG(0xE000EF50u) /* B2.2.7 table B2-1: invalidate I-cache to PoU */
#define SCB_DCISW   CM7_REG(0xE000EF60u) /* B2.2.7 table B2-1: invalidate D-cache by set/way */

/* SysTick (ARMv7-M ARM B3.3, table B3-7) */
#define SYST_CSR    CM7_REG(0xE000E010u) /* B3.3.3 control and status */
#define SYST_RVR    CM7_REG(0xE000E014u) /* B3.3.4 reload value (24 bits) */
#define SYST_CVR    CM7_REG(0xE000E018u) /* B3.3.5 current value, counts down */
#define SYST_CSR_ENABLE    (1u << 0)
#define SYST_CSR_CLKSOURCE (1u << 2)     /* 1: processor clock */

/* Data Watchpoint and Trace (ARMv7-M ARM C1.8, table C1-21; M7 TRM 8.1) */
#define DWT_CTRL    CM7_REG(0xE0001000u) /* C1.8.7 bit 0 CYCCNTENA */
#define DWT_CYCCNT  CM7_REG(0xE0001004u) /* C1.8.8 cycle count */
#define DWT_LAR     CM7_REG(0xE0001FB0u) /* CoreSight lock access (key 0xC5ACCE55) */

/* Barriers (ARMv7-M ARM A7.7.26 DSB, A7.7.33 ISB) */
#define CM7_DSB() __asm__ volatile("dsb 0xF" ::: "memory")
#define CM7_ISB() __asm__ volatile("isb 0xF" ::: "memory")

/* Grant full access to CP10/CP11 (the FPU) before the first float
 * instruction (ARMv7-M ARM B3.2.20; targets.md: otherwise it faults). */
static inline void cm7_fpu_enable(void)
{
    SCB_CPACR |= (0xFu << 20);
    CM7_DSB();
    CM7_ISB();
}

/* SysTick free-running over 24 bits from the processor clock (B3.3). */
static inline void cm7_systick_free_run(void)
{
    SYST_CSR = 0u;
    SYST_RVR = 0x00FFFFFFu;
    SYST_CVR = 0u;
    SYST_CSR = SYST_CSR_CLKSOURCE | SYST_CSR_ENABLE;
}

/* Up-counting view of SysTick, modulo 2^24. */
static inline uint32_t cm7_systick_up(void)
{
    return (0x00FFFFFFu - SYST_CVR) & 0x00FFFFFFu;
}

/* Linker-script symbols every Cortex-M7 port defines (see its .ld file). */
extern uint32_t _estack;                      /* initial stack pointer */
extern uint32_t _sidata, _sdata, _edata;      /* .data: load, start, end */
extern uint32_t _siitcm, _sitcm, _eitcm;      /* .itcm_text: load, start, end */
extern uint32_t _sidtcm, _sdtcm, _edtcm;      /* .dtcm_rodata: load, start, end */
extern uint32_t _sbss, _ebss;                 /* .bss */

/* Unhandled exception: the port reports and stops (startup_cm7.c). */
void cm7_fault(uint32_t vector);

#endif /* CM7_H */
