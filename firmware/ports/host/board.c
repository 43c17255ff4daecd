/*
 * board.c -- host port: console on stdout, CLOCK_MONOTONIC as the cycle
 * counter, exit status as the result.  POSIX.1-2001 for clock_gettime and
 * poll.  Serial protocol builds (MPC_HIL): the protocol runs on stdin/stdout
 * (a pseudo-terminal the harness opens as the serial port), stdout fully
 * buffered and flushed whenever the program waits for input; the program
 * ends when the link closes.
 */
#define _POSIX_C_SOURCE 200112L

#include <errno.h>
#include <poll.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

#include "console.h"
#include "port.h"

/* Longest wait for input in port_read (ms): no busy loop on a shared host. */
#define PORT_READ_WAIT_MS 2

void port_init(void)
{
#if defined(MPC_HIL)
    (void)setvbuf(stdout, NULL, _IOFBF, 16384u);
#endif
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

uint16_t port_read(uint16_t *octets, uint16_t max)
{
    unsigned char buf[256];
    struct pollfd pfd;
    size_t want = (max < sizeof buf) ? (size_t)max : sizeof buf;
    ssize_t n;
    ssize_t i;
    (void)fflush(stdout);
    pfd.fd = STDIN_FILENO;
    pfd.events = POLLIN;
    pfd.revents = 0;
    if (poll(&pfd, 1u, PORT_READ_WAIT_MS) <= 0) {
        return 0u;
    }
    n = read(STDIN_FILENO, buf, want);
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) {
        return 0u;
    }
    if (n <= 0) { /* end of file or the terminal hung up: the link is gone */
        (void)fflush(stdout);
        exit(0);
    }
    for (i = 0; i < n; ++i) {
        octets[i] = (uint16_t)buf[i];
    }
    return (uint16_t)n;
}
