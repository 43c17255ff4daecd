/*
 * port_config.h -- QEMU mps2-an385 (emulated Cortex-M3, no FPU), see port.h.
 * SysTick runs from the 25 MHz processor clock; under -icount shift=N it
 * counts exactly instructions * 2^N / 40 (as on qemu-m7; checked by the CAL
 * line of port_report): the unit is ticks, not M3 cycles.
 */
#ifndef PORT_CONFIG_H
#define PORT_CONFIG_H

#define PORT_BOARD "qemu-m3"
#define PORT_CORE_CLOCK_HZ 25000000u
#define PORT_ICOUNT_SHIFT 10
#define PORT_CYCLE_UNIT "systick-ticks"
#define PORT_CYCLES_MASK 0x00FFFFFFu

#endif /* PORT_CONFIG_H */
