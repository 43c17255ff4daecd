/*
 * board.c -- host port: console on stdout, CLOCK_MONOTONIC as the cycle
 * counter, exit status as the result.  POSIX.1b for clock_gettime.
 */
#define _POSIX_C_SOURCE 199309L

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "console.h"
#include "port.h"

void port_init(void)
{
}

void port_putc(uint16_t c)
{
    (void)putchar((int)(c & 0xFFu));
}

uint32_t port_cycles(void)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint32_t)((uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec);
}

void port_report(void)
{
    console_puts("PORT host timer=clock_monotonic");
    console_eol();
}

void port_exit(uint16_t code)
{
    console_puts("EXIT");
    console_kv_u32("code", code);
    console_eol();
    (void)fflush(stdout);
    exit((int)code);
}
