/*
 * board.c -- QEMU mps2-an385 board layer (ARM AN385: Cortex-M3, no FPU;
 * QEMU hw/arm/mps2.c): CMSDK APB UART0 console, SysTick cycle counter,
 * semihosting exit.  The same peripherals as the qemu-m7 port (mps2-an500):
 *
 * CMSDK APB UART (Arm Cortex-M System Design Kit TRM, DDI 0479, section
 * 4.3 "UART"): DATA +0x00, STATE +0x04 (bit 0 TX buffer full), CTRL +0x08
 * (bit 0 TX enable), BAUDDIV +0x10 (>= 16).  UART0 is at 0x40004000 on
 * mps2-an385 (AN385 memory map, APB subsystem), its clock 25 MHz.
 *
 * This port runs the self-test only (no serial protocol build: port_read
 * returns nothing).  Its purpose is a core without an FPU: the fixed-point
 * step is integer C, so its image needs no floating-point instruction.
 */
#include <stdint.h>

#include "console.h"
#include "m3.h"
#include "port.h"

#define UART0_BASE    0x40004000u
#define UART0_DATA    M3_REG(UART0_BASE + 0x00u)
#define UART0_STATE   M3_REG(UART0_BASE + 0x04u)
#define UART0_CTRL    M3_REG(UART0_BASE + 0x08u)
#define UART0_BAUDDIV M3_REG(UART0_BASE + 0x10u)
#define UART_STATE_TXFULL (1u << 0)
#define UART_CTRL_TXEN    (1u << 0)

/* Semihosting (Arm "Semihosting for AArch32 and AArch64", 5.2 SYS_EXIT_EXTENDED). */
#define SEMIHOST_SYS_EXIT_EXTENDED 0x20u
#define SEMIHOST_ADP_APPLICATION_EXIT 0x20026u

/* Instructions in the calibration sled (port_report). */
#define CAL_NOPS 1024u

void port_init(void)
{
    UART0_BAUDDIV = 217u; /* 25 MHz / 115200; no effect in emulation */
    UART0_CTRL = UART_CTRL_TXEN;
    m3_systick_free_run();
}

void port_putc(uint16_t c)
{
    while ((UART0_STATE & UART_STATE_TXFULL) != 0u) {
    }
    UART0_DATA = (uint32_t)(c & 0xFFu);
}

uint32_t port_cycles(void)
{
    return m3_systick_up();
}

uint16_t port_read(uint16_t *octets, uint16_t max)
{
    (void)octets;
    (void)max;
    return 0u;
}

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
    console_puts("PORT mps2-an385 uart0=0x40004000 timer=systick(clksource=cpu,25MHz) fpu=none");
    console_kv_hex32("cpuid", SCB_CPUID);
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

void m3_fault(uint32_t vector)
{
    console_puts("FAULT");
    console_kv_u32("vector", vector);
    console_eol();
    semihost_exit(3u);
    for (;;) {
    }
}
