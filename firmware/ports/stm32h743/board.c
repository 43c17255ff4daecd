/*
 * board.c -- STM32H743 (NUCLEO-H743ZI2) board layer: supply, clock tree,
 * flash wait states, caches, DWT cycle counter, USART3 console (ST-LINK
 * virtual COM port on PD8 TX / PD9 RX, AF7: board user manual UM2407).
 *
 * Clock: PLL1 from HSE (8 MHz bypass clock from the ST-LINK MCO, UM2407
 * "HSE clock") or, if HSE never becomes ready, from HSI (64 MHz);
 * reference 2 MHz (DIVM1 = 4 or 32), VCO 800 MHz (DIVN1 = 400), P = 2:
 * SYSCLK = CPU = 400 MHz at voltage scale 1 (RM0433 6.6.2: 400 MHz max at
 * VOS1 on every silicon revision), AXI/AHB 200 MHz (HPRE /2), APB1-4
 * 100 MHz, flash 2 wait states with WRHIGHFREQ = 2 (RM0433 table 17).
 */
#include <stdint.h>

#include "cm7.h"
#include "console.h"
#include "port.h"
#include "stm32h743_regs.h"

#define HSE_TIMEOUT 2000000u     /* polls (~100 ms at the 64 MHz reset clock) */
#define USART3_KERNEL_HZ 100000000u /* rcc_pclk1 (RM0433 8.5.x: USART234578SEL reset value) */
#if defined(MPC_HIL)
#define CONSOLE_BAUD 921600u /* serial protocol builds: BRR 109, 0.4 % off (ST-LINK VCP) */
#else
#define CONSOLE_BAUD 115200u
#endif

static uint16_t pll_from_hse;

/* Wait until (reg & mask) == want, at most `polls` reads; return 1 if it happened. */
static uint16_t wait_bits(volatile uint32_t *reg, uint32_t mask, uint32_t want, uint32_t polls)
{
    while (polls > 0u) {
        if ((*reg & mask) == want) {
            return 1u;
        }
        --polls;
    }
    return 0u;
}

/* RM0433 6.4.1 / 6.8.4: LDO supply, then voltage scale 1 (6.6.2). */
static void power_init(void)
{
    PWR_CR3 = (PWR_CR3 & ~(PWR_CR3_SCUEN | PWR_CR3_LDOEN | PWR_CR3_BYPASS)) | PWR_CR3_LDOEN;
    (void)wait_bits(&PWR_CSR1, PWR_CSR1_ACTVOSRDY, PWR_CSR1_ACTVOSRDY, 0xFFFFFFFFu);
    PWR_D3CR = (PWR_D3CR & ~PWR_D3CR_VOS_MASK) | PWR_D3CR_VOS_SCALE1;
    (void)wait_bits(&PWR_D3CR, PWR_D3CR_VOSRDY, PWR_D3CR_VOSRDY, 0xFFFFFFFFu);
}

/* RM0433 8.5.5 (PLLs), 8.5.6 (system clock switch), 4.3.8 (flash latency). */
static void clock_init(void)
{
    uint32_t divm = 32u, src = 0u; /* HSI 64 MHz / 32 */
    RCC_CR |= RCC_CR_HSEBYP | RCC_CR_HSEON;
    if (wait_bits(&RCC_CR, RCC_CR_HSERDY, RCC_CR_HSERDY, HSE_TIMEOUT) != 0u) {
        divm = 4u; /* HSE 8 MHz / 4 */
        src = 2u;
        pll_from_hse = 1u;
    } else {
        RCC_CR &= ~(RCC_CR_HSEON | RCC_CR_HSEBYP);
    }
    RCC_PLLCKSELR = (RCC_PLLCKSELR & ~((0x3Fu << 4) | 3u)) | (divm << 4) | src;
    RCC_PLL1DIVR = (400u - 1u) | ((2u - 1u) << 9) | ((4u - 1u) << 16) | ((2u - 1u) << 24);
    /* PLL1: integer mode, wide VCO (VCOSEL 0), input range 2-4 MHz (RGE 01), P output on */
    RCC_PLLCFGR = (RCC_PLLCFGR & ~0xFu & ~(7u << 16)) | (1u << 2) | (1u << 16);
    RCC_CR |= RCC_CR_PLL1ON;
    (void)wait_bits(&RCC_CR, RCC_CR_PLL1RDY, RCC_CR_PLL1RDY, 0xFFFFFFFFu);
    /* flash: 2 wait states, WRHIGHFREQ 2 for a 200 MHz AXI clock at VOS1; read back */
    FLASH_ACR = (FLASH_ACR & ~0x3Fu) | 2u | (2u << 4);
    (void)wait_bits(&FLASH_ACR, 0x3Fu, 2u | (2u << 4), 0xFFFFFFFFu);
    /* CPU /1, AXI/AHB /2 (HPRE 1000), APB3 /2; APB1, APB2 /2; APB4 /2 (PPRE 100) */
    RCC_D1CFGR = (0u << 8) | (4u << 4) | 8u;
    RCC_D2CFGR = (4u << 8) | (4u << 4);
    RCC_D3CFGR = (4u << 4);
    RCC_CFGR = (RCC_CFGR & ~7u) | 3u;
    (void)wait_bits(&RCC_CFGR, 7u << 3, 3u << 3, 0xFFFFFFFFu);
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

/* ARMv7-M ARM C1.6.5 (TRCENA), C1.8.7 (CYCCNTENA); M7 TRM: the DWT lock. */
static void dwt_init(void)
{
    SCB_DEMCR |= SCB_DEMCR_TRCENA;
    DWT_LAR = 0xC5ACCE55u;
    DWT_CYCCNT = 0u;
    DWT_CTRL |= 1u;
}

/* USART3 on PD8/PD9 AF7 (UM2407 ST-LINK VCP; RM0433 11.4, 48.5), CONSOLE_BAUD 8N1. */
static void console_init(void)
{
    RCC_AHB4ENR |= (1u << 3);
    RCC_APB1LENR |= (1u << 18);
    (void)RCC_APB1LENR; /* RM0433 8.5.10: a read after enabling a clock */
    GPIOD_MODER = (GPIOD_MODER & ~(0xFu << 16)) | (0xAu << 16);     /* PD8, PD9 alternate */
    GPIOD_OSPEEDR = (GPIOD_OSPEEDR & ~(0xFu << 16)) | (0x5u << 16); /* medium speed */
    GPIOD_AFRH = (GPIOD_AFRH & ~0xFFu) | 0x77u;                    /* AF7 = USART3 */
    USART3_CR1 = 0u;
    USART3_BRR = (USART3_KERNEL_HZ + CONSOLE_BAUD / 2u) / CONSOLE_BAUD;
    USART3_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE;
}

void port_init(void)
{
    power_init();
    clock_init();
    caches_init();
    dwt_init();
    console_init();
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
    console_puts(" icache=on dcache=on fpu=fpv5-d16 cycles=dwt step=itcm tables=dtcm");
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

void cm7_fault(uint32_t vector)
{
    console_puts("FAULT");
    console_kv_u32("vector", vector);
    console_eol();
    for (;;) {
        __asm__ volatile("wfi");
    }
}
