/*
 * port.h -- what every board port (firmware/ports/<board>/) provides to the
 * shared runtime.  The port's own port_config.h defines:
 *
 *   PORT_BOARD          board name, a string ("qemu-m7", "stm32h743", ...)
 *   PORT_CORE_CLOCK_HZ  core clock in Hz (uint32_t constant)
 *   PORT_CYCLE_UNIT     unit of port_cycles(), a string ("cycles", "ticks", "ns")
 *   PORT_CYCLES_MASK    port_cycles() counts up modulo PORT_CYCLES_MASK + 1
 *
 * C99; only fixed-width integer types cross this interface (C28x: char and
 * int are 16 bits, see docs/targets.md).
 */
#ifndef MPC_PORT_H
#define MPC_PORT_H

#include <stdint.h>

#include "port_config.h"

/* Clocks, caches, FPU, console and cycle counter: everything before main's work. */
void port_init(void);

/* Send one character (its low 8 bits) to the console; blocks while the transmitter is full. */
void port_putc(uint16_t c);

/* Up-counting cycle counter, modulo PORT_CYCLES_MASK + 1 (see port_config.h). */
uint32_t port_cycles(void);

/* Print port-specific lines after HELLO (clock set-up, FPU mode, calibration). */
void port_report(void);

/* Stop: report `code` (0 = pass) to whatever runs the board, then never return. */
void port_exit(uint16_t code);

/* Serial protocol builds only (MPC_HIL, runtime/hil_proto.h): copy up to `max`
 * received octets that are already waiting into `octets` (one octet per word,
 * low 8 bits) and return how many; 0 when nothing is waiting.  Polled: it does
 * not wait for input (the host port may sleep a few ms instead of spinning). */
uint16_t port_read(uint16_t *octets, uint16_t max);

#endif /* MPC_PORT_H */
