/*
 * port_config.h -- STM32H743 on the NUCLEO-H743ZI2 (see port.h).
 * Core clock 400 MHz (PLL1 at voltage scale 1, board.c); the cycle counter
 * is DWT_CYCCNT, 32 bits, counting core clock cycles.
 */
#ifndef PORT_CONFIG_H
#define PORT_CONFIG_H

#define PORT_BOARD "stm32h743"
#define PORT_CORE_CLOCK_HZ 400000000u
#define PORT_CYCLE_UNIT "cycles"
#define PORT_CYCLES_MASK 0xFFFFFFFFu

#endif /* PORT_CONFIG_H */
