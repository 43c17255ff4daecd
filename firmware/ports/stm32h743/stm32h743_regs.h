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

#endif /* STM32H743_REGS_H */
