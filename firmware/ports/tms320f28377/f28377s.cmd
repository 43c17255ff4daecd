/*
 * f28377s.cmd -- linker command file for the TMS320F28377S (TI C2000 linker,
 * EABI).  Memory map: data sheet SPRS881 "Memory map" and SPRUHX5 chapter 3.
 * Addresses and lengths are in 16-bit words.  Flash sections are aligned to
 * 8 words (128-bit ECC words).  The controller step (.TI.ramfunc, set by the
 * generated code's #pragma CODE_SECTION) and flash_init are copied from
 * flash to GS RAM at boot (BINIT copy table).
 * BEGIN holds section codestart: one LB (2 words, codestart.c), checked
 * by tests/firmware/test_port_layout.py since cl2000 does not run here.
 */
MEMORY
{
    BEGIN      : origin = 0x080000, length = 0x000002  /* boot-to-flash entry */
    RAMM0      : origin = 0x000123, length = 0x0002DD
    RAMM1      : origin = 0x000400, length = 0x000400  /* stack */
    RAMLS0_5   : origin = 0x008000, length = 0x003000
    RAMD0_1    : origin = 0x00B000, length = 0x001000
    RAMGS0_15  : origin = 0x00C000, length = 0x010000
    FLASH      : origin = 0x080002, length = 0x03FFEE  /* sectors A-N */
    RESET      : origin = 0x3FFFC0, length = 0x000002
}

SECTIONS
{
    codestart    : > BEGIN
    .text        : > FLASH, ALIGN(8)
    .cinit       : > FLASH, ALIGN(8)
    .switch      : > FLASH, ALIGN(8)
    .init_array  : > FLASH, ALIGN(8)
    .const       : > FLASH, ALIGN(8)   /* test data: up to ~200K words */
    .binit       : > FLASH, ALIGN(8)
    .TI.ramfunc  : LOAD = FLASH, RUN = RAMGS0_15, table(BINIT), ALIGN(8)
    .stack       : > RAMM1
    .bss         : > RAMLS0_5
    .bss:output  : > RAMLS0_5
    .data        : > RAMLS0_5
    .sysmem      : > RAMD0_1
    .reset       : > RESET, TYPE = DSECT
}
