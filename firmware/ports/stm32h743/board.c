/*
 * board.c -- STM32H743 (NUCLEO-H743ZI2) board layer: MPU background region,
 * caches, supply, clock tree, flash wait states, DWT cycle counter, USART3
 * console (ST-LINK virtual COM port on PD8 TX / PD9 RX, AF7: board user
 * manual UM2407), and a blink code on the red user LED LD3 (PB14, UM2407)
 * for a failure the console cannot report.
 *
 * Clock: PLL1 from HSE (8 MHz bypass clock from the ST-LINK MCO, UM2407
 * "HSE clock") or, if HSE never becomes ready, from HSI (64 MHz);
 * reference 2 MHz (DIVM1 = 4 or 32), VCO 800 MHz (DIVN1 = 400), P = 2:
 * SYSCLK = CPU = 400 MHz at voltage scale 1 (RM0433 6.6.2: 400 MHz max at
 * VOS1 on every silicon revision), AXI/AHB 200 MHz (HPRE /2), APB1-4
 * 100 MHz, flash 2 wait states with WRHIGHFREQ = 2 (RM0433 table 17).
 *
 * Order (ST's CubeH7 templates: MPU_Config, CPU_CACHE_Enable, then
 * SystemClock_Config): MPU, caches, supply and voltage scale, clocks, flash
 * latency, DWT, console.  Every wait on a status bit is bounded
 * (h7_wait_polls below).  Deviations from ST's sequence, with their reason:
 *  - timeouts count polls, not HAL milliseconds (no SysTick time base before
 *    the clock is set); each bound is at least the HAL's time (see below);
 *  - HSE not ready: PLL1 runs from HSI instead of returning an error (the
 *    board then still runs; the PORT line says which source);
 *  - a failed wait stops the board (ERROR line and EXIT code=4 when the CPU
 *    still runs from HSI with reset prescalers, so the console's baud rate
 *    is known; then the blink code) instead of returning HAL_ERROR;
 *  - ST's SystemInit also fixes the AXI SRAM read issuing capability on
 *    silicon revision Y and disables FMC bank 1: not done, the image uses
 *    neither AXI SRAM nor the FMC, and the MPU background region keeps
 *    speculative reads away from the FMC banks.
 */
#include <stdint.h>

#include "cm7.h"
#include "console.h"
#include "port.h"
#include "stm32h743_regs.h"

#define HSI_HZ 64000000u            /* RM0433 8.5.2: HSI after reset (HSIDIV /1) */
#define CORE_HZ 400000000u          /* PLL1 P, see above */
#define USART3_KERNEL_HZ 100000000u /* rcc_pclk1 (RM0433 8.5.x: USART234578SEL reset value) */
#if defined(MPC_HIL)
#define CONSOLE_BAUD 921600u /* serial protocol builds: BRR 109, 0.4 % off (ST-LINK VCP) */
#else
#define CONSOLE_BAUD 115200u
#endif

/* Bounded waits.  A poll (load of an RCC/PWR/FLASH register, compare,
 * decrement, branch) takes at least 4 core cycles, so at the 64 MHz HSI
 * the CPU runs on during every wait below it polls at most 16 times a
 * microsecond: WAIT_MS(n) polls last at least n ms (at most a few times
 * that: a register read over the D3 AHB takes more cycles).  The HAL's
 * timeouts these replace (stm32h7xx_hal_rcc.h / _pwr_ex.c, values as
 * recalled, not re-checked here): HSE 100 ms (HSE_STARTUP_TIMEOUT), PLL
 * 2 ms, clock switch 5000 ms, supply/VOS 1000 ms; the lock and switch
 * themselves take microseconds (PLL lock: data sheet, tens of us). */
#define POLLS_PER_MS 16000u
#define WAIT_MS(ms) ((uint32_t)(ms) * POLLS_PER_MS)

/* What a wait is for: index into h7_wait_polls / h7_stage_name.  A failed
 * wait W blinks W + 1 times (docs/targets.md, first flash). */
#define W_SUPPLY 0u     /* PWR_CSR1 ACTVOSRDY: LDO supply configuration taken */
#define W_VOS 1u        /* PWR_D3CR VOSRDY: voltage scale 1 reached */
#define W_HSI 2u        /* RCC_CR HSIRDY (clock defaults) */
#define W_SW_HSI 3u     /* RCC_CFGR SWS = HSI (clock defaults) */
#define W_PLLS_OFF 4u   /* RCC_CR PLL1-3RDY and HSERDY clear (clock defaults) */
#define W_PLL1_LOCK 5u  /* RCC_CR PLL1RDY */
#define W_FLASH_WS 6u   /* FLASH_ACR latency read back */
#define W_SW_PLL1 7u    /* RCC_CFGR SWS = PLL1 */
#define W_HSE 8u        /* RCC_CR HSERDY: not a failure, PLL1 then runs from HSI */
#define W_COUNT 9u
#define BLINK_FAULT 9u  /* an exception before the console works */

/* Poll limits; a table (not inlined constants) so that the image carries
 * them: tests/firmware/test_port_layout.py reads it back from the ELF. */
const uint32_t h7_wait_polls[W_COUNT] = {
    WAIT_MS(100u), /* W_SUPPLY */
    WAIT_MS(100u), /* W_VOS */
    WAIT_MS(10u),  /* W_HSI */
    WAIT_MS(100u), /* W_SW_HSI */
    WAIT_MS(10u),  /* W_PLLS_OFF */
    WAIT_MS(10u),  /* W_PLL1_LOCK */
    WAIT_MS(1u),   /* W_FLASH_WS */
    WAIT_MS(100u), /* W_SW_PLL1 */
    WAIT_MS(100u), /* W_HSE */
};

static const char *const h7_stage_name[W_COUNT] = {
    "supply-actvosrdy", "vos1-vosrdy", "hsi-ready", "switch-to-hsi", "plls-off",
    "pll1-lock", "flash-latency", "switch-to-pll1", "hse-ready",
};

static uint16_t pll_from_hse;
static uint16_t console_ready;
static uint32_t core_hz = HSI_HZ; /* what the CPU runs at (blink timing) */

static void h7_halt(uint16_t code) __attribute__((noreturn, noinline)); /* noinline: tests stop at its entry */
static void h7_fail(uint16_t stage) __attribute__((noreturn));

/* Wait until (reg & mask) == want, at most h7_wait_polls[stage] reads; 1 if
 * it happened.  noipa: one loop, indexed at run time (no per-call clone). */
__attribute__((noipa)) static uint16_t h7_wait(uint16_t stage, volatile uint32_t *reg, uint32_t mask,
                                               uint32_t want)
{
    uint32_t polls = h7_wait_polls[stage];
    while (polls > 0u) {
        if ((*reg & mask) == want) {
            return 1u;
        }
        --polls;
    }
    return 0u;
}

/* A wait that must succeed: on timeout the board stops (h7_fail). */
static void h7_need(uint16_t stage, volatile uint32_t *reg, uint32_t mask, uint32_t want)
{
    if (h7_wait(stage, reg, mask, want) == 0u) {
        h7_fail(stage);
    }
}

/* ST's MPU_Config (cm7.h), before the caches. */
static void mpu_init(void)
{
    cm7_mpu_background();
}

/* ARMv7-M ARM B2.2.7: invalidate, then enable the L1 caches (M7 TRM 5.3). */
static void caches_init(void)
{
    uint32_t ccsidr, sets, ways, set, way;
    CM7_DSB();
    CM7_ISB();
    SCB_ICIALLU = 0u;
    CM7_DSB();
    CM7_ISB();
    SCB_CCR |= SCB_CCR_IC;
    CM7_DSB();
    CM7_ISB();
    SCB_CSSELR = 0u; /* level 1 data cache */
    CM7_DSB();
    ccsidr = SCB_CCSIDR;
    sets = ((ccsidr >> 13) & 0x7FFFu) + 1u;
    ways = ((ccsidr >> 3) & 0x3FFu) + 1u;
    for (set = 0u; set < sets; ++set) {
        for (way = 0u; way < ways; ++way) {
            SCB_DCISW = (way << 30) | (set << 5); /* 4 ways, 32-byte lines */
        }
    }
    CM7_DSB();
    SCB_CCR |= SCB_CCR_DC;
    CM7_DSB();
    CM7_ISB();
}

/* RM0433 6.4.1 / 6.8.4: LDO supply, then voltage scale 1 (6.6.2). */
static void power_init(void)
{
    PWR_CR3 = (PWR_CR3 & ~(PWR_CR3_SCUEN | PWR_CR3_LDOEN | PWR_CR3_BYPASS)) | PWR_CR3_LDOEN;
    h7_need(W_SUPPLY, &PWR_CSR1, PWR_CSR1_ACTVOSRDY, PWR_CSR1_ACTVOSRDY);
    PWR_D3CR = (PWR_D3CR & ~PWR_D3CR_VOS_MASK) | PWR_D3CR_VOS_SCALE1;
    h7_need(W_VOS, &PWR_D3CR, PWR_D3CR_VOSRDY, PWR_D3CR_VOSRDY);
}

/* The reset clock configuration, as ST's SystemInit restores it: after a
 * reset this changes nothing, but a debugger that loads the image and
 * starts it without a reset leaves PLL1 running as the system clock, and
 * PLL1's dividers cannot be changed while it runs (RM0433 8.7.13), nor the
 * PLL source while any PLL runs (8.7.11). */
static void clock_defaults(void)
{
    RCC_CR |= RCC_CR_HSION;
    h7_need(W_HSI, &RCC_CR, RCC_CR_HSIRDY, RCC_CR_HSIRDY);
    RCC_CFGR &= ~RCC_CFGR_SW_MASK;
    h7_need(W_SW_HSI, &RCC_CFGR, RCC_CFGR_SWS_MASK, 0u);
    RCC_D1CFGR = 0u;
    RCC_D2CFGR = 0u;
    RCC_D3CFGR = 0u;
    RCC_CR &= ~(RCC_CR_PLL1ON | RCC_CR_PLL2ON | RCC_CR_PLL3ON | RCC_CR_HSEON);
    h7_need(W_PLLS_OFF, &RCC_CR, RCC_CR_PLL1RDY | RCC_CR_PLL2RDY | RCC_CR_PLL3RDY | RCC_CR_HSERDY, 0u);
}

/* RM0433 8.5.5 (PLLs), 8.5.6 (system clock switch), 4.3.8 (flash latency). */
static void clock_init(void)
{
    uint32_t divm = 32u, src = 0u; /* HSI 64 MHz / 32 */
    clock_defaults();
    /* HSEBYP is written while HSE is off, then HSEON (RM0433 8.7.2) */
    RCC_CR |= RCC_CR_HSEBYP;
    RCC_CR |= RCC_CR_HSEON;
    if (h7_wait(W_HSE, &RCC_CR, RCC_CR_HSERDY, RCC_CR_HSERDY) != 0u) {
        divm = 4u; /* HSE 8 MHz / 4 */
        src = 2u;
        pll_from_hse = 1u;
    } else {
        RCC_CR &= ~RCC_CR_HSEON;
        RCC_CR &= ~RCC_CR_HSEBYP;
    }
    RCC_PLLCKSELR = (RCC_PLLCKSELR & ~((0x3Fu << 4) | 3u)) | (divm << 4) | src;
    RCC_PLL1DIVR = (400u - 1u) | ((2u - 1u) << 9) | ((4u - 1u) << 16) | ((2u - 1u) << 24);
    /* PLL1: integer mode, wide VCO (VCOSEL 0), input range 2-4 MHz (RGE 01), P output on */
    RCC_PLLCFGR = (RCC_PLLCFGR & ~0xFu & ~(7u << 16)) | (1u << 2) | (1u << 16);
    RCC_CR |= RCC_CR_PLL1ON;
    h7_need(W_PLL1_LOCK, &RCC_CR, RCC_CR_PLL1RDY, RCC_CR_PLL1RDY);
    /* flash: 2 wait states, WRHIGHFREQ 2 for a 200 MHz AXI clock at VOS1; read back */
    FLASH_ACR = (FLASH_ACR & ~0x3Fu) | 2u | (2u << 4);
    h7_need(W_FLASH_WS, &FLASH_ACR, 0x3Fu, 2u | (2u << 4));
    /* CPU /1, AXI/AHB /2 (HPRE 1000), APB3 /2; APB1, APB2 /2; APB4 /2 (PPRE 100) */
    RCC_D1CFGR = (0u << 8) | (4u << 4) | 8u;
    RCC_D2CFGR = (4u << 8) | (4u << 4);
    RCC_D3CFGR = (4u << 4);
    RCC_CFGR = (RCC_CFGR & ~RCC_CFGR_SW_MASK) | 3u;
    h7_need(W_SW_PLL1, &RCC_CFGR, RCC_CFGR_SWS_MASK, 3u << 3);
    core_hz = CORE_HZ;
}

/* ARMv7-M ARM C1.6.5 (TRCENA), C1.8.7 (CYCCNTENA); M7 TRM: the DWT lock. */
static void dwt_init(void)
{
    SCB_DEMCR |= SCB_DEMCR_TRCENA;
    DWT_LAR = 0xC5ACCE55u;
    DWT_CYCCNT = 0u;
    DWT_CTRL |= 1u;
}

/* USART3 on PD8/PD9 AF7 (UM2407 ST-LINK VCP; RM0433 11.4, 48.5), CONSOLE_BAUD 8N1
 * from a kernel clock of kernel_hz (rcc_pclk1). */
static void console_init(uint32_t kernel_hz)
{
    RCC_AHB4ENR |= (1u << 3);
    RCC_APB1LENR |= (1u << 18);
    (void)RCC_APB1LENR; /* RM0433 8.5.10: a read after enabling a clock */
    GPIOD_MODER = (GPIOD_MODER & ~(0xFu << 16)) | (0xAu << 16);     /* PD8, PD9 alternate */
    GPIOD_OSPEEDR = (GPIOD_OSPEEDR & ~(0xFu << 16)) | (0x5u << 16); /* medium speed */
    GPIOD_AFRH = (GPIOD_AFRH & ~0xFFu) | 0x77u;                    /* AF7 = USART3 */
    USART3_CR1 = 0u;
    USART3_BRR = (kernel_hz + CONSOLE_BAUD / 2u) / CONSOLE_BAUD;
    USART3_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE;
    console_ready = 1u;
}

void port_init(void)
{
    mpu_init();
    caches_init();
    power_init();
    clock_init();
    dwt_init();
    console_init(USART3_KERNEL_HZ);
}

/* A wait failed.  If the CPU still runs from HSI with the reset prescalers
 * (every stage but the HSI ones and the switch to PLL1), the console works
 * at a 64 MHz kernel clock: ERROR and EXIT lines, then the blink code. */
static void h7_fail(uint16_t stage)
{
    if (stage != W_HSI && stage != W_SW_HSI && stage != W_SW_PLL1) {
        console_init(HSI_HZ);
        console_puts("ERROR port_init");
        console_kv_str("board", PORT_BOARD);
        console_kv_str("stage", h7_stage_name[stage]);
        console_kv_str("sysclk", "hsi-64MHz");
        console_kv_u32("blink", (uint32_t)stage + 1u);
        console_eol();
        console_puts("EXIT");
        console_kv_u32("code", 4u);
        console_eol();
        while ((USART3_ISR & USART_ISR_TC) == 0u) {
        }
    }
    h7_halt((uint16_t)(stage + 1u));
}

/* Busy wait of `ms` milliseconds at core_hz (DWT cycle counter). */
static void delay_ms(uint32_t ms)
{
    uint32_t start, cycles = ms * (core_hz / 1000u);
    SCB_DEMCR |= SCB_DEMCR_TRCENA;
    DWT_LAR = 0xC5ACCE55u;
    DWT_CTRL |= 1u;
    start = DWT_CYCCNT;
    while ((DWT_CYCCNT - start) < cycles) {
    }
}

/* Blink code on LD3 (red, PB14, active high: UM2407) forever: `code` flashes
 * of 0.2 s (0.3 s apart), then 1.5 s dark.  Timing assumes core_hz (after a
 * failed switch to PLL1 the real clock is unknown: count the flashes). */
static void h7_halt(uint16_t code)
{
    uint16_t i;
    RCC_AHB4ENR |= (1u << 1);
    (void)RCC_AHB4ENR;
    GPIOB_MODER = (GPIOB_MODER & ~(3u << 28)) | (1u << 28);
    for (;;) {
        for (i = 0u; i < code; ++i) {
            GPIOB_BSRR = 1u << 14;
            delay_ms(200u);
            GPIOB_BSRR = 1u << (14 + 16);
            delay_ms(300u);
        }
        delay_ms(1500u);
    }
}

void port_putc(uint16_t c)
{
    while ((USART3_ISR & USART_ISR_TXE) == 0u) {
    }
    USART3_TDR = (uint32_t)(c & 0xFFu);
}

#if defined(MPC_HIL)
/* Polled receive: whatever RDR holds while RXNE is set (one octet per
 * read); an overrun (ORE) is cleared, the lost octets show as a bad frame
 * the host sends again. */
uint16_t port_read(uint16_t *octets, uint16_t max)
{
    uint16_t n = 0u;
    if ((USART3_ISR & USART_ISR_ORE) != 0u) {
        USART3_ICR = USART_ICR_ORECF;
    }
    while (n < max && (USART3_ISR & USART_ISR_RXNE) != 0u) {
        octets[n] = (uint16_t)(USART3_RDR & 0xFFu);
        ++n;
    }
    return n;
}
#endif

uint32_t port_cycles(void)
{
    return DWT_CYCCNT;
}

void port_report(void)
{
    console_puts("PORT stm32h743 core=400MHz vos=1 supply=ldo flash_ws=2 axi=200MHz apb=100MHz");
    console_kv_str("pll1_src", (pll_from_hse != 0u) ? "hse-bypass-8MHz" : "hsi-64MHz");
    console_puts(" mpu=background icache=on dcache=on fpu=fpv5-d16 cycles=dwt step=itcm tables=dtcm");
    console_eol();
}

void port_exit(uint16_t code)
{
    console_puts("EXIT");
    console_kv_u32("code", code);
    console_eol();
    while ((USART3_ISR & USART_ISR_TC) == 0u) {
    }
    for (;;) {
        __asm__ volatile("wfi");
    }
}

/* An exception: FAULT line if the console works, and the blink code
 * BLINK_FAULT in any case (before console_init it is the only sign). */
void cm7_fault(uint32_t vector)
{
    if (console_ready != 0u) {
        console_puts("FAULT");
        console_kv_u32("vector", vector);
        console_eol();
        while ((USART3_ISR & USART_ISR_TC) == 0u) {
        }
    }
    h7_halt(BLINK_FAULT);
}
