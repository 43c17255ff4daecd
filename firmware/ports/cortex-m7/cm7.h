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
#define SCB_SHCSR   CM7_REG(0xE000ED24u) /* B3.2.13 system handler control and state */
#define SCB_SHCSR_MEMFAULTENA (1u << 16)
#define SCB_CCSIDR  CM7_REG(0xE000ED80u) /* B4.8.3 cache size ID */
#define SCB_CSSELR  CM7_REG(0xE000ED84u) /* B4.8.4 cache size selection */
#define SCB_CPACR   CM7_REG(0xE000ED88u) /* B3.2.20 coprocessor access control: CP10/CP11 bits 23:20 */
#define SCB_DEMCR   CM7_REG(0xE000EDFCu) /* C1.6.5 debug exception and monitor control */
#define SCB_DEMCR_TRCENA (1u << 24)
#define FPU_MVFR0   CM7_REG(0xE000EF40u) /* B4.6.5 media and VFP feature register 0 */
#define SCB_ICIALLU CM7_REG(0xE000EF50u) /* B2.2.7 table B2-1: invalidate I-cache to PoU */
#define SCB_DCISW   CM7_REG(0xE000EF60u) /* B2.2.7 table B2-1: invalidate D-cache by set/way */

/* Memory protection unit (ARMv7-M ARM B3.5, table B3-11) */
#define MPU_TYPE    CM7_REG(0xE000ED90u) /* B3.5.5 DREGION[15:8]: number of regions */
#define MPU_CTRL    CM7_REG(0xE000ED94u) /* B3.5.6 */
#define MPU_RNR     CM7_REG(0xE000ED98u) /* B3.5.7 region number */
#define MPU_RBAR    CM7_REG(0xE000ED9Cu) /* B3.5.8 region base address */
#define MPU_RASR    CM7_REG(0xE000EDA0u) /* B3.5.9 region attribute and size */
#define MPU_CTRL_ENABLE     (1u << 0)
#define MPU_CTRL_PRIVDEFENA (1u << 2)    /* default map for privileged accesses outside every region */
#define MPU_RASR_ENABLE     (1u << 0)
#define MPU_RASR_SIZE(n)    ((uint32_t)(n) << 1) /* region of 2^(n+1) bytes */
#define MPU_RASR_SRD(m)     ((uint32_t)(m) << 8) /* subregion (1/8 of the region) disable mask */
#define MPU_RASR_S          (1u << 18)
#define MPU_RASR_AP_NONE    (0u << 24)   /* no access, privileged or not */
#define MPU_RASR_XN         (1u << 28)

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

/* The background region ST installs on the STM32H7 (its CubeH7 templates'
 * MPU_Config; AN4838/AN4839) against the Cortex-M7's speculative reads: the
 * default memory map (B3.1.1) makes 0x60000000-0x9FFFFFFF Normal memory, so
 * the core may read there speculatively, and on a device with nothing (or
 * an unconfigured FMC/QUADSPI) behind it such a read can stall the bus.
 * Region 0 covers the 4 GB as no access, execute never (TEX 000, C 0, B 0:
 * strongly ordered), with subregions 0 (code, ITCM, flash), 1 (SRAM, DTCM),
 * 2 (peripherals) and 7 (system) disabled (SRD 0x87), so those keep the
 * default map; PRIVDEFENA keeps the default map for everything no region
 * covers.  Run it with the caches still off (ST enables them after it).
 * Afterwards an access to 0x60000000-0xDFFFFFFF is a MemManage fault. */
static inline void cm7_mpu_background(void)
{
    __asm__ volatile("dmb 0xF" ::: "memory");
    SCB_SHCSR &= ~SCB_SHCSR_MEMFAULTENA;
    MPU_CTRL = 0u;
    MPU_RNR = 0u;
    MPU_RBAR = 0x00000000u;
    MPU_RASR = MPU_RASR_XN | MPU_RASR_AP_NONE | MPU_RASR_S | MPU_RASR_SRD(0x87u) | MPU_RASR_SIZE(31u) |
               MPU_RASR_ENABLE;
    MPU_CTRL = MPU_CTRL_PRIVDEFENA | MPU_CTRL_ENABLE;
    SCB_SHCSR |= SCB_SHCSR_MEMFAULTENA;
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

/* Reset_Handler's C part, after SP is set (startup_cm7.c). */
void cm7_reset(void) __attribute__((noreturn));

#endif /* CM7_H */
