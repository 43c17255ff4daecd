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

/* Semihosting (Arm "Semihosting for AArch32 and AArch64", 5.2 SYS_EXIT_EXTENDED). */
#define SEMIHOST_SYS_EXIT_EXTENDED 0x20u
#define SEMIHOST_ADP_APPLICATION_EXIT 0x20026u

/* Instructions in the calibration sled (port_report). */
#define CAL_NOPS 1024u

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

/* Exactly CAL_NOPS instructions plus the return, and the return alone. */
static __attribute__((noipa)) void cal_sled(void)
{
    __asm__ volatile(".rept 1024\n\tnop\n\t.endr" ::: "memory");
}

static __attribute__((noipa)) void cal_empty(void)
{
    __asm__ volatile("" ::: "memory");
}

/* One non-inlined timing sequence for both functions (same code around the call). */
static __attribute__((noipa)) uint32_t cal_time(void (*fn)(void))
{
    uint32_t t0, t1;
    __asm__ volatile("" ::: "memory");
    t0 = port_cycles();
    __asm__ volatile("" ::: "memory");
    fn();
    __asm__ volatile("" ::: "memory");
    t1 = port_cycles();
    return (t1 - t0) & PORT_CYCLES_MASK;
}

void port_report(void)
{
    uint32_t sled = cal_time(cal_sled);
    uint32_t empty = cal_time(cal_empty);
    console_puts("PORT mps2-an500 uart0=0x40004000 timer=systick(clksource=cpu,25MHz)");
    console_kv_hex32("mvfr0", FPU_MVFR0);
    console_eol();
    /* the host checks ticks = CAL_NOPS * 2^shift / 40 (targets.md) */
    console_puts("CAL");
    console_kv_u32("nops", CAL_NOPS);
    console_kv_u32("ticks", (sled - empty) & PORT_CYCLES_MASK);
    console_eol();
}

static void semihost_exit(uint32_t code)
{
    volatile uint32_t block[2];
    register uint32_t r0 __asm__("r0") = SEMIHOST_SYS_EXIT_EXTENDED;
    register uint32_t r1 __asm__("r1") = (uint32_t)(uintptr_t)block;
    block[0] = SEMIHOST_ADP_APPLICATION_EXIT;
    block[1] = code;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
}

void port_exit(uint16_t code)
{
    console_puts("EXIT");
    console_kv_u32("code", code);
    console_eol();
    semihost_exit(code);
    for (;;) {
    }
}

void cm7_fault(uint32_t vector)
{
    console_puts("FAULT");
    console_kv_u32("vector", vector);
    console_eol();
    semihost_exit(3u);
    for (;;) {
    }
}
