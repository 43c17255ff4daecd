/*
 * stm32h743_regs.h -- the STM32H743 peripheral registers board.c uses,
 * written from RM0433 rev 8 ("STM32H742, STM32H743/753 and STM32H750
 * reference manual"); no vendor SDK.  Section numbers are RM0433's.
 */
#ifndef STM32H743_REGS_H
#define STM32H743_REGS_H

#include "cm7.h"

/* 2.3.2 memory map: AHB4 (D3) peripherals */
#define PWR_BASE   0x58024800u /* 6.8 PWR registers */
#define RCC_BASE   0x58024400u /* 8.7 RCC registers */
#define GPIOB_BASE 0x58020400u /* 11.4 GPIO registers */
#define GPIOD_BASE 0x58020C00u
#define FLASH_BASE_REGS 0x52002000u /* 4.9 FLASH registers (bank 1 view) */
#define USART3_BASE 0x40004800u /* 48.7 USART registers (APB1) */

/* 6.8.4 PWR control register 3: supply configuration (written once after reset) */
#define PWR_CR3    CM7_REG(PWR_BASE + 0x0Cu)
#define PWR_CR3_BYPASS (1u << 0)
#define PWR_CR3_LDOEN  (1u << 1)
#define PWR_CR3_SCUEN  (1u << 2)
/* 6.8.3 PWR control status register 1 */
#define PWR_CSR1   CM7_REG(PWR_BASE + 0x04u)
#define PWR_CSR1_ACTVOSRDY (1u << 13)
/* 6.8.6 PWR D3 domain control register: VOS[15:14] (11 = scale 1), VOSRDY bit 13 */
#define PWR_D3CR   CM7_REG(PWR_BASE + 0x18u)
#define PWR_D3CR_VOS_MASK (3u << 14)
#define PWR_D3CR_VOS_SCALE1 (3u << 14)
#define PWR_D3CR_VOSRDY (1u << 13)

/* 8.7.2 RCC source control register */
#define RCC_CR     CM7_REG(RCC_BASE + 0x00u)
#define RCC_CR_HSION  (1u << 0)
#define RCC_CR_HSIRDY (1u << 2)
#define RCC_CR_HSEON  (1u << 16)
#define RCC_CR_HSERDY (1u << 17)
#define RCC_CR_HSEBYP (1u << 18)
#define RCC_CR_PLL1ON (1u << 24)
#define RCC_CR_PLL1RDY (1u << 25)
#define RCC_CR_PLL2ON (1u << 26)
#define RCC_CR_PLL2RDY (1u << 27)
#define RCC_CR_PLL3ON (1u << 28)
#define RCC_CR_PLL3RDY (1u << 29)
/* 8.7.6 RCC clock configuration register: SW[2:0], SWS[5:3] (0 = HSI, 3 = PLL1) */
#define RCC_CFGR   CM7_REG(RCC_BASE + 0x10u)
#define RCC_CFGR_SW_MASK  (7u << 0)
#define RCC_CFGR_SWS_MASK (7u << 3)
/* 8.7.8-8.7.10 domain 1/2/3 clock configuration registers */
#define RCC_D1CFGR CM7_REG(RCC_BASE + 0x18u) /* D1CPRE[11:8], D1PPRE[6:4], HPRE[3:0] */
#define RCC_D2CFGR CM7_REG(RCC_BASE + 0x1Cu) /* D2PPRE2[10:8], D2PPRE1[6:4] */
#define RCC_D3CFGR CM7_REG(RCC_BASE + 0x20u) /* D3PPRE[6:4] */
/* 8.7.11 PLLs clock source selection: PLLSRC[1:0] (0 HSI, 2 HSE), DIVM1[9:4] */
#define RCC_PLLCKSELR CM7_REG(RCC_BASE + 0x28u)
/* 8.7.12 PLLs configuration: PLL1VCOSEL bit 1, PLL1RGE[3:2], DIVP1EN bit 16, DIVQ1EN 17, DIVR1EN 18 */
#define RCC_PLLCFGR CM7_REG(RCC_BASE + 0x2Cu)
/* 8.7.13 PLL1 dividers: DIVN1[8:0] = N-1, DIVP1[15:9] = P-1, DIVQ1[22:16], DIVR1[30:24] */
#define RCC_PLL1DIVR CM7_REG(RCC_BASE + 0x30u)
/* 8.7.43 AHB4 clock enable (GPIOBEN bit 1, GPIODEN bit 3); 8.7.45 APB1L clock enable (USART3EN bit 18) */
#define RCC_AHB4ENR  CM7_REG(RCC_BASE + 0xE0u)
#define RCC_APB1LENR CM7_REG(RCC_BASE + 0xE8u)

/* 4.9.1 FLASH access control register: LATENCY[3:0], WRHIGHFREQ[5:4] */
#define FLASH_ACR  CM7_REG(FLASH_BASE_REGS + 0x00u)

/* 11.4.1 mode (2 bits per pin, 01 = output, 10 = alternate), 11.4.7 BSRR (bits 15:0 set, 31:16 reset) */
#define GPIOB_MODER   CM7_REG(GPIOB_BASE + 0x00u)
#define GPIOB_BSRR    CM7_REG(GPIOB_BASE + 0x18u)

/* 11.4.1 mode (2 bits per pin, 10 = alternate), 11.4.3 speed, 11.4.10 AFRH (4 bits per pin 8..15) */
#define GPIOD_MODER   CM7_REG(GPIOD_BASE + 0x00u)
#define GPIOD_OSPEEDR CM7_REG(GPIOD_BASE + 0x08u)
#define GPIOD_AFRH    CM7_REG(GPIOD_BASE + 0x24u)

/* 48.7.1 CR1 (UE bit 0, RE bit 2, TE bit 3), 48.7.5 BRR, 48.7.10 ISR (TXE/TXFNF bit 7), 48.7.14 TDR */
#define USART3_CR1 CM7_REG(USART3_BASE + 0x00u)
#define USART3_BRR CM7_REG(USART3_BASE + 0x0Cu)
#define USART3_ISR CM7_REG(USART3_BASE + 0x1Cu)
#define USART3_TDR CM7_REG(USART3_BASE + 0x28u)
/* Receive (RM0433 48.7.10 ISR: RXNE/RXFNE bit 5 "read data register not
 * empty", ORE bit 3 overrun; 48.7.11 ICR +0x20: ORECF bit 3 clears ORE;
 * 48.7.13 RDR +0x24: received data in bits 8:0, reading it clears RXNE). */
#define USART3_ICR CM7_REG(USART3_BASE + 0x20u)
#define USART3_RDR CM7_REG(USART3_BASE + 0x24u)
#define USART_ISR_RXNE (1u << 5)
#define USART_ISR_ORE  (1u << 3)
#define USART_ICR_ORECF (1u << 3)
#define USART_CR1_UE (1u << 0)
#define USART_CR1_RE (1u << 2)
#define USART_CR1_TE (1u << 3)
#define USART_ISR_TXE (1u << 7)
#define USART_ISR_TC  (1u << 6)

/* ---- PWM timers, GPIO and ADC of the generated example interrupt routine
 * (<prefix>_isr_example.c, docs/modulator.md); board.c uses none of them.
 * Addresses: RM0433 2.3.2 memory map (APB2: TIM1 0x40010000, TIM8
 * 0x40010400; AHB1: ADC1 0x40022000; AHB4: GPIOA 0x58020000, GPIOC
 * 0x58020800, GPIOE 0x58021000); register offsets from RM0433's TIM1/TIM8,
 * GPIO and ADC register maps. */
#define TIM1_BASE  0x40010000u
#define TIM8_BASE  0x40010400u
#define ADC1_BASE  0x40022000u
#define GPIOA_BASE 0x58020000u
#define GPIOC_BASE 0x58020800u
#define GPIOE_BASE 0x58021000u
/* RCC_APB2ENR (RCC + 0xF0): TIM1EN bit 0, TIM8EN bit 1 */
#define RCC_APB2ENR CM7_REG(RCC_BASE + 0xF0u)
#define RCC_APB2ENR_TIM1EN (1u << 0)
#define RCC_APB2ENR_TIM8EN (1u << 1)
/* RCC_AHB4ENR (above): GPIOAEN bit 0, GPIOBEN bit 1, GPIOCEN bit 2, GPIOEEN bit 4 */
#define RCC_AHB4ENR_GPIOAEN (1u << 0)
#define RCC_AHB4ENR_GPIOBEN (1u << 1)
#define RCC_AHB4ENR_GPIOCEN (1u << 2)
#define RCC_AHB4ENR_GPIOEEN (1u << 4)
/* GPIO registers of any port: MODER 0x00, OSPEEDR 0x08, AFRL 0x20, AFRH 0x24 */
#define GPIO_MODER(base)   CM7_REG((base) + 0x00u)
#define GPIO_OSPEEDR(base) CM7_REG((base) + 0x08u)
#define GPIO_AFRL(base)    CM7_REG((base) + 0x20u)
#define GPIO_AFRH(base)    CM7_REG((base) + 0x24u)
/* TIM1/TIM8 (advanced-control timers) registers */
#define TIM_CR1(base)   CM7_REG((base) + 0x00u) /* CEN bit 0, DIR bit 4 (read-only when centre-aligned), CMS 6:5, ARPE 7 */
#define TIM_CR2(base)   CM7_REG((base) + 0x04u) /* MMS 6:4, OISx/OISxN 8.., MMS2 23:20 */
#define TIM_SMCR(base)  CM7_REG((base) + 0x08u) /* SMS 2:0, TS 6:4, MSM 7 */
#define TIM_SR(base)    CM7_REG((base) + 0x10u)
#define TIM_EGR(base)   CM7_REG((base) + 0x14u) /* UG bit 0 */
#define TIM_CCMR1(base) CM7_REG((base) + 0x18u) /* OC1PE bit 3, OC1M 6:4; OC2PE bit 11, OC2M 14:12 */
#define TIM_CCMR2(base) CM7_REG((base) + 0x1Cu) /* OC3PE bit 3, OC3M 6:4 */
#define TIM_CCER(base)  CM7_REG((base) + 0x20u) /* CCxE 4(x-1), CCxP +1, CCxNE +2, CCxNP +3 */
#define TIM_CNT(base)   CM7_REG((base) + 0x24u)
#define TIM_PSC(base)   CM7_REG((base) + 0x28u)
#define TIM_ARR(base)   CM7_REG((base) + 0x2Cu)
#define TIM_RCR(base)   CM7_REG((base) + 0x30u)
#define TIM_CCR1(base)  CM7_REG((base) + 0x34u)
#define TIM_CCR2(base)  CM7_REG((base) + 0x38u)
#define TIM_CCR3(base)  CM7_REG((base) + 0x3Cu)
#define TIM_BDTR(base)  CM7_REG((base) + 0x44u) /* DTG 7:0, OSSI 10, OSSR 11, AOE 14, MOE 15 */
#define TIM_CR1_CEN  (1u << 0)
#define TIM_CR1_DIR  (1u << 4)
#define TIM_BDTR_AOE (1u << 14)
#define TIM_BDTR_MOE (1u << 15)
/* ADC1: ISR 0x00 (JEOS bit 6, cleared by writing 1), injected data JDR1..JDR4 at 0x80..0x8C */
#define ADC_ISR(base)  CM7_REG((base) + 0x00u)
#define ADC_JDR1(base) CM7_REG((base) + 0x80u)
#define ADC_JDR2(base) CM7_REG((base) + 0x84u)
#define ADC_JDR3(base) CM7_REG((base) + 0x88u)
#define ADC_JDR4(base) CM7_REG((base) + 0x8Cu)
#define ADC_ISR_JEOS (1u << 6)

#endif /* STM32H743_REGS_H */
