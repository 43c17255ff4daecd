/*
 * port_config.h -- TMS320F28377S on the LAUNCHXL-F28377S (see port.h).
 * SYSCLK 200 MHz (10 MHz crystal, SYSPLL x40 / 2, board.c); cycles are
 * CpuTimer1 ticks at SYSCLK (counting down, read as ~TIM: counting up).
 */
#ifndef PORT_CONFIG_H
#define PORT_CONFIG_H

#define PORT_BOARD "tms320f28377"
#define PORT_CORE_CLOCK_HZ 200000000u
#define PORT_CYCLE_UNIT "cycles"
#define PORT_CYCLES_MASK 0xFFFFFFFFu

#endif /* PORT_CONFIG_H */
