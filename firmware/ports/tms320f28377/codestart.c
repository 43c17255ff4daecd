/*
 * codestart.c -- entry point at the flash boot address 0x080000 (boot ROM
 * "boot to flash", SPRUHX5 4.x): disable the watchdog (WDCR at 0x7029:
 * WDDIS bit 6 with check bits 5:3 = 101b, SPRUHX5 3.12) so the C runtime's
 * initialisation cannot be cut short by a watchdog reset, then branch to
 * the TI runtime's boot routine _c_int00.  Written as file-scope asm
 * statements (TI C28x compiler: "The asm statement" may appear outside
 * functions) so that the port ships as C sources only; f28377s.cmd places
 * section "codestart" at BEGIN.
 */
#if defined(__TI_COMPILER_VERSION__)
__asm("        .ref    _c_int00");
__asm("        .global code_start");
__asm("        .sect   \"codestart\"");
__asm("        .retain");
__asm("code_start:");
__asm("        EALLOW");
__asm("        MOVZ    DP, #7029h >> 6");
__asm("        MOV     @7029h, #0068h");
__asm("        EDIS");
__asm("        LB      _c_int00");
#else
/* host (C28x type model): nothing to run; keep the translation unit non-empty */
typedef int codestart_host_model_unused;
#endif
