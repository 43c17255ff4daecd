/*
 * mps2_qemu.h -- what the emulated MPS2 boards (qemu-m7: mps2-an500,
 * qemu-m3: mps2-an385) share: the instruction-count calibration line and the
 * semihosting exit.  Each board's port_report prints its PORT line, then
 * mps2_report_cal(); port_exit is defined once, in mps2_qemu.c.
 */
#ifndef MPS2_QEMU_H
#define MPS2_QEMU_H

#include <stdint.h>

/* Prints "CAL nops=... ticks=...": the host checks ticks = CAL_NOPS * 2^shift / 40 (targets.md). */
void mps2_report_cal(void);

/* Ends QEMU with exit status ``code`` (semihosting SYS_EXIT_EXTENDED); does not return. */
void mps2_semihost_exit(uint32_t code);

#endif
