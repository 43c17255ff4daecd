/*
 * board.c -- QEMU mps2-an500 board layer (ARM AN500 / QEMU hw/arm/mps2.c):
 * CMSDK APB UART0 console, SysTick cycle counter, semihosting exit.
 *
 * CMSDK APB UART (Arm Cortex-M System Design Kit TRM, DDI 0479, section
 * 4.3 "UART"): DATA +0x00, STATE +0x04 (bit 0 TX buffer full), CTRL +0x08
 * (bit 0 TX enable), BAUDDIV +0x10 (>= 16).  UART0 is at 0x40004000 on
 * mps2-an500 (AN500 memory map); its clock is 25 MHz.
 * Receive (same TRM section; QEMU hw/char/cmsdk-apb-uart.c models it so):
 * STATE bit 1 is "RX buffer full", CTRL bit 1 "RX enable"; reading DATA
 * returns the received octet in bits 7:0 and clears RX buffer full.  The
 * receive buffer holds one octet: QEMU offers the next octet from the
 * character device only once it is read (no overrun, the host is held back).
 *
 * Serial protocol builds (MPC_HIL): port_cycles() counts instructions.  The
 * harness runs QEMU with -icount shift=PORT_ICOUNT_SHIFT (10): one instruction
 * is 1024 ns of virtual time, SysTick ticks every 40 ns (25 MHz), so after J
 * instructions SysTick has counted floor(J * 25.6) ticks and
 * J = ceil(ticks * 5 / 128) exactly (the rounding error is < 1/25.6).  The
 * 24-bit SysTick is extended to 64 bits in software; a wrap missed between
 * two calls costs 2^24 ticks = 655360 instructions, a whole number, so the
 * difference of two readings stays exact.  Branch-free: every call takes the
 * same instructions, which the overhead subtraction removes.
 */
#include <stdint.h>

#include "cm7.h"
#include "console.h"
#include "mps2_qemu.h"
#include "port.h"

#define UART0_BASE    0x40004000u
#define UART0_DATA    CM7_REG(UART0_BASE + 0x00u)
#define UART0_STATE   CM7_REG(UART0_BASE + 0x04u)
#define UART0_CTRL    CM7_REG(UART0_BASE + 0x08u)
#define UART0_BAUDDIV CM7_REG(UART0_BASE + 0x10u)
#define UART_STATE_TXFULL (1u << 0)
#define UART_STATE_RXFULL (1u << 1)
#define UART_CTRL_TXEN    (1u << 0)
#define UART_CTRL_RXEN    (1u << 1)


void port_init(void)
{
    UART0_BAUDDIV = 217u; /* 25 MHz / 115200; no effect in emulation */
#if defined(MPC_HIL)
    UART0_CTRL = UART_CTRL_TXEN | UART_CTRL_RXEN;
#else
    UART0_CTRL = UART_CTRL_TXEN;
#endif
    cm7_systick_free_run();
}

void port_putc(uint16_t c)
{
    while ((UART0_STATE & UART_STATE_TXFULL) != 0u) {
    }
    UART0_DATA = (uint32_t)(c & 0xFFu);
}

#if defined(MPC_HIL)
uint32_t port_cycles(void)
{
    static uint32_t last;
    static uint64_t ticks;
    uint32_t now = cm7_systick_up();
    ticks += (uint64_t)((now - last) & 0x00FFFFFFu);
    last = now;
    return (uint32_t)((ticks * 5u + 127u) >> 7);
}

uint16_t port_read(uint16_t *octets, uint16_t max)
{
    uint16_t n = 0u;
    while (n < max && (UART0_STATE & UART_STATE_RXFULL) != 0u) {
        octets[n] = (uint16_t)(UART0_DATA & 0xFFu);
        ++n;
    }
    return n;
}
#else
uint32_t port_cycles(void)
{
    return cm7_systick_up();
}
#endif

void port_report(void)
{
    console_puts("PORT mps2-an500 uart0=0x40004000 timer=systick(clksource=cpu,25MHz)");
    console_kv_hex32("mvfr0", FPU_MVFR0);
    console_eol();
    mps2_report_cal();
}

void cm7_fault(uint32_t vector)
{
    console_puts("FAULT");
    console_kv_u32("vector", vector);
    console_eol();
    mps2_semihost_exit(3u);
    for (;;) {
    }
}
