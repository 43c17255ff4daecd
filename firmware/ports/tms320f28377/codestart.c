/*
 * codestart.c -- entry point at the flash boot address 0x080000 (boot ROM
 * "boot to flash", SPRUHX5 4.x).  f28377s.cmd gives section "codestart" the
 * 2-word region BEGIN, so it holds one long branch (LB, 2 words) and
 * nothing else, as TI's own CodeStartBranch does.  The branch goes to
 * codestart_wd_off in .text, which disables the watchdog (WDCR at 0x7029:
 * WDDIS bit 6 with check bits 5:3 = 101b, SPRUHX5 3.12) so the C runtime's
 * initialisation cannot be cut short by a watchdog reset, and branches to
 * the TI runtime's boot routine _c_int00.  OBJMODE is set first, as TI's
 * start-up does (the boot ROM leaves it set; harmless).
 *
 * Written as file-scope asm statements (TI C28x compiler: "The asm
 * statement" may appear outside functions) so that the port ships as C
 * sources only.  NOT ASSEMBLED HERE (no cl2000): tests/firmware/
 * test_port_layout.py counts the words each instruction below places in
 * "codestart" and fails if they exceed BEGIN's length in f28377s.cmd; keep
 * one instruction per asm statement so it can.
 */
#if defined(__TI_COMPILER_VERSION__)
__asm("        .ref    _c_int00");
__asm("        .global code_start");
__asm("        .sect   \"codestart\"");
__asm("        .retain");
__asm("code_start:");
__asm("        LB      codestart_wd_off");
__asm("        .text");
__asm("codestart_wd_off:");
__asm("        SETC    OBJMODE");
__asm("        EALLOW");
__asm("        MOVZ    DP, #7029h >> 6");
__asm("        MOV     @7029h, #0068h");
__asm("        EDIS");
__asm("        LB      _c_int00");
#else
/* host (C28x type model): nothing to run; keep the translation unit non-empty */
typedef int codestart_host_model_unused;
#endif
