/*
 * mps2_qemu.c -- the emulated MPS2 boards' calibration and exit (see
 * mps2_qemu.h): a sled of exactly CAL_NOPS instructions timed against an
 * empty call with the board's port_cycles(), and the exit through
 * semihosting (Arm "Semihosting for AArch32 and AArch64", 5.2
 * SYS_EXIT_EXTENDED), which QEMU turns into its exit status.
 */
#include <stdint.h>

#include "console.h"
#include "mps2_qemu.h"
#include "port.h"

#define SEMIHOST_SYS_EXIT_EXTENDED 0x20u
#define SEMIHOST_ADP_APPLICATION_EXIT 0x20026u

/* the calibration sled's length (instructions) */
#define CAL_NOPS 1024u

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

void mps2_report_cal(void)
{
    uint32_t sled = cal_time(cal_sled);
    uint32_t empty = cal_time(cal_empty);
    console_puts("CAL");
    console_kv_u32("nops", CAL_NOPS);
    console_kv_u32("ticks", (sled - empty) & PORT_CYCLES_MASK);
    console_eol();
}

void mps2_semihost_exit(uint32_t code)
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
    mps2_semihost_exit(code);
    for (;;) {
    }
}
