/*
 * console.c -- number and string formatting for the console (see console.h).
 */
#include "console.h"

#include "port.h"

void console_putc(uint16_t c)
{
    port_putc(c);
}

void console_puts(const char *text)
{
    while (*text != '\0') {
        port_putc((uint16_t)((uint16_t)*text & 0xFFu));
        ++text;
    }
}

void console_put_u32(uint32_t value)
{
    uint16_t digits[10];
    uint16_t n = 0u;
    do {
        digits[n] = (uint16_t)(value % 10u);
        value /= 10u;
        ++n;
    } while (value != 0u);
    while (n > 0u) {
        --n;
        port_putc((uint16_t)('0' + digits[n]));
    }
}

void console_put_hex(uint32_t value, uint16_t digits)
{
    static const char hex[] = "0123456789abcdef";
    uint16_t i;
    if (digits > 8u) {
        digits = 8u;
    }
    for (i = digits; i > 0u; --i) {
        uint32_t nibble = (value >> (4u * (uint32_t)(i - 1u))) & 0xFu;
        port_putc((uint16_t)hex[nibble]);
    }
}

void console_put_hex32(uint32_t value)
{
    console_puts("0x");
    console_put_hex(value, 8u);
}

void console_kv_u32(const char *key, uint32_t value)
{
    port_putc((uint16_t)' ');
    console_puts(key);
    port_putc((uint16_t)'=');
    console_put_u32(value);
}

void console_kv_hex32(const char *key, uint32_t value)
{
    port_putc((uint16_t)' ');
    console_puts(key);
    port_putc((uint16_t)'=');
    console_put_hex32(value);
}

void console_kv_str(const char *key, const char *value)
{
    port_putc((uint16_t)' ');
    console_puts(key);
    port_putc((uint16_t)'=');
    console_puts(value);
}

void console_eol(void)
{
    port_putc((uint16_t)'\r');
    port_putc((uint16_t)'\n');
}
