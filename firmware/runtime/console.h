/*
 * console.h -- minimal text output over the port's console (UART / SCI /
 * stdout).  No printf: no varargs, no floating point, no double promotion;
 * numbers are printed as unsigned decimal or 8-digit hex.
 *
 * Strings are ordinary C string literals; on C28x each char is a 16-bit unit
 * and only its low 8 bits are sent (port_putc).
 */
#ifndef MPC_CONSOLE_H
#define MPC_CONSOLE_H

#include <stdint.h>

/* One character. */
void console_putc(uint16_t c);

/* A NUL-terminated string. */
void console_puts(const char *text);

/* Unsigned decimal. */
void console_put_u32(uint32_t value);

/* "0x" and exactly 8 lower-case hex digits. */
void console_put_hex32(uint32_t value);

/* Exactly `digits` lower-case hex digits (1..8), no prefix. */
void console_put_hex(uint32_t value, uint16_t digits);

/* " key=value" pairs, the format of every summary line. */
void console_kv_u32(const char *key, uint32_t value);
void console_kv_hex32(const char *key, uint32_t value);
void console_kv_str(const char *key, const char *value);

/* End the line ("\r\n": terminal friendly, the host parser strips '\r'). */
void console_eol(void);

#endif /* MPC_CONSOLE_H */
