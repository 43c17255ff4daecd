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
#include "mps2_qemu.h"
#include "m3.h"
#include "port.h"

#define UART0_BASE    0x40004000u
#define UART0_DATA    M3_REG(UART0_BASE + 0x00u)
#define UART0_STATE   M3_REG(UART0_BASE + 0x04u)
#define UART0_CTRL    M3_REG(UART0_BASE + 0x08u)
#define UART0_BAUDDIV M3_REG(UART0_BASE + 0x10u)
#define UART_STATE_TXFULL (1u << 0)
#define UART_CTRL_TXEN    (1u << 0)


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

void port_report(void)
{
    console_puts("PORT mps2-an385 uart0=0x40004000 timer=systick(clksource=cpu,25MHz) fpu=none");
    console_kv_hex32("cpuid", SCB_CPUID);
    console_eol();
    mps2_report_cal();
}

void m3_fault(uint32_t vector)
{
    console_puts("FAULT");
    console_kv_u32("vector", vector);
    console_eol();
    mps2_semihost_exit(3u);
    for (;;) {
    }
}
