/*
 * port_config.h -- the host port (a plain C program, used for sanitizer
 * builds), see port.h.  The cycle counter is CLOCK_MONOTONIC in ns (32 bits).
 */
#ifndef PORT_CONFIG_H
#define PORT_CONFIG_H

#define PORT_BOARD "host"
#define PORT_CORE_CLOCK_HZ 0u /* unknown: time is in ns */
#define PORT_CYCLE_UNIT "ns"
#define PORT_CYCLES_MASK 0xFFFFFFFFu

#endif /* PORT_CONFIG_H */
