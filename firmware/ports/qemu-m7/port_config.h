/*
 * port_config.h -- QEMU mps2-an500 (emulated Cortex-M7), see port.h.
 * SysTick runs from the 25 MHz processor clock; under -icount shift=N it
 * counts exactly instructions * 2^N / 40 (docs/targets.md, checked by
 * the CAL line of port_report): the unit is ticks, not M7 cycles.
 * Serial protocol builds (MPC_HIL) convert to instructions (board.c) for
 * -icount shift=PORT_ICOUNT_SHIFT, counting over 32 bits.
 */
#ifndef PORT_CONFIG_H
#define PORT_CONFIG_H

#define PORT_BOARD "qemu-m7"
#define PORT_CORE_CLOCK_HZ 25000000u
#define PORT_ICOUNT_SHIFT 10
#if defined(MPC_HIL)
#define PORT_CYCLE_UNIT "instructions" /* INFO carries up to 16 characters */
#define PORT_CYCLES_MASK 0xFFFFFFFFu
#else
#define PORT_CYCLE_UNIT "systick-ticks"
#define PORT_CYCLES_MASK 0x00FFFFFFu
#endif

#endif /* PORT_CONFIG_H */
