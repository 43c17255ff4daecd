/*
 * c28x_regs.h -- the TMS320F2837xS registers board.c uses, written from the
 * technical reference manual SPRUHX5 ("TMS320F2837xS Microcontrollers TRM",
 * rev. F) and the data sheet SPRS881; no controlSUITE/C2000Ware files.
 * Addresses are in 16-bit words (C28x data space); section numbers are
 * SPRUHX5's.  Registers are 16 bits unless noted.
 *
 * NOT BUILT HERE: cl2000 is not installable on this project's machines.
 * The C is compiled on the host under the C28x type model
 * (-DMPC_C28X_TYPE_MODEL, tests/firmware); check each value on the board.
 * With -DMPC_C28X_HOST_SIM as well, the registers are a simulated register
 * file of the host test (tests/firmware/c28x_sim.c), which runs port_init's
 * sequences: order, delays, bounded waits and failure reports.
 */
#ifndef C28X_REGS_H
#define C28X_REGS_H

#include <stdint.h>

#if defined(MPC_C28X_HOST_SIM)
volatile void *c28x_sim_reg(uint32_t addr);       /* the simulated register at addr */
void c28x_sim_event(uint16_t what, uint16_t cycles); /* 'A' EALLOW, 'D' EDIS, 'N' NOP cycles, 'S' ESTOP0 */
#define C28X_REG16(addr) (*(volatile uint16_t *)c28x_sim_reg(addr))
#define C28X_REG32(addr) (*(volatile uint32_t *)c28x_sim_reg(addr))
#else
#define C28X_REG16(addr) (*(volatile uint16_t *)(uintptr_t)(addr))
#define C28X_REG32(addr) (*(volatile uint32_t *)(uintptr_t)(addr))
#endif

#if defined(__TI_COMPILER_VERSION__)
#define C28X_EALLOW() __asm(" EALLOW") /* 3.2.x: write access to protected registers */
#define C28X_EDIS() __asm(" EDIS")
#define C28X_RNDF32_NEAREST() __asm(" SETFLG RNDF32=1") /* SPRUEO2 (FPU32): STF.RNDF32 = round to nearest */
#define C28X_ESTOP() __asm(" ESTOP0")
/* RPT #n || NOP: the NOP n + 1 times, one cycle each (SPRU430 "RPT"): fixed
 * delays in SYSCLK cycles, as TI's start-up code uses them. */
#define C28X_NOP8() __asm(" RPT #7 || NOP")      /* flash: pipeline flush after the last write */
#define C28X_NOP21() __asm(" RPT #20 || NOP")    /* SYSPLL: after PLLCLKEN changes */
#define C28X_NOP100() __asm(" RPT #99 || NOP")   /* one spin of the bounded waits (board.c) */
#define C28X_NOP201() __asm(" RPT #200 || NOP")  /* SYSPLL: regulator settling before the last divider */
#elif defined(MPC_C28X_HOST_SIM)
#define C28X_EALLOW() c28x_sim_event('A', 0u)
#define C28X_EDIS() c28x_sim_event('D', 0u)
#define C28X_RNDF32_NEAREST() ((void)0)
#define C28X_ESTOP() c28x_sim_event('S', 0u)
#define C28X_NOP8() c28x_sim_event('N', 8u)
#define C28X_NOP21() c28x_sim_event('N', 21u)
#define C28X_NOP100() c28x_sim_event('N', 100u)
#define C28X_NOP201() c28x_sim_event('N', 201u)
#elif defined(MPC_C28X_TYPE_MODEL)
#define C28X_EALLOW() ((void)0)
#define C28X_EDIS() ((void)0)
#define C28X_RNDF32_NEAREST() ((void)0)
#define C28X_ESTOP() ((void)0)
#define C28X_NOP8() ((void)0)
#define C28X_NOP21() ((void)0)
#define C28X_NOP100() ((void)0)
#define C28X_NOP201() ((void)0)
#else
#error "tms320f28377 port: build with cl2000 (build.sh) or check on the host with -DMPC_C28X_TYPE_MODEL"
#endif

/* 3.14 CPU timers: CpuTimer1Regs at 0x0C08 (memory map, table 3-1) */
#define CPUTIMER1_TIM C28X_REG32(0x0C08u) /* 3.14.x TIM: counter (32 bits) */
#define CPUTIMER1_PRD C28X_REG32(0x0C0Au) /* PRD: period (32 bits) */
#define CPUTIMER1_TCR C28X_REG16(0x0C0Cu) /* TCR: TSS bit 4, TRB bit 5, SOFT bit 10, FREE bit 11 */
#define CPUTIMER1_TPR C28X_REG16(0x0C0Eu) /* TPR: prescaler low (0: SYSCLK) */
#define CPUTIMER1_TPRH C28X_REG16(0x0C0Fu) /* TPRH: prescaler high */
#define TCR_TSS (1u << 4)
#define TCR_TRB (1u << 5)
#define TCR_FREE (1u << 11)

/* 3.15 clock configuration registers: ClkCfgRegs at 0x5D200 */
#define CLK_CLKSRCCTL1 C28X_REG32(0x5D208u)  /* OSCCLKSRCSEL[1:0] (0 = INTOSC2, 1 = XTAL), XTALOFF bit 4 */
#define CLK_SYSPLLCTL1 C28X_REG32(0x5D20Eu)  /* PLLEN bit 0, PLLCLKEN bit 1 */
#define CLK_SYSPLLMULT C28X_REG32(0x5D214u)  /* IMULT[6:0], FMULT[9:8]; writing it starts a lock */
#define CLK_SYSPLLSTS C28X_REG32(0x5D216u)   /* LOCKS bit 0, SLIPS bit 1 */
#define CLK_SYSCLKDIVSEL C28X_REG32(0x5D222u) /* PLLSYSCLKDIV[5:0]: divide by 2*value (0: by 1) */
#define CLK_LOSPCP C28X_REG32(0x5D22Cu)      /* LSPCLKDIV[2:0]: 0 = SYSCLK/1, n = SYSCLK/2n, 2 = /4 (reset) */
/* Missing clock detect (3.7.x "Missing clock detection"): MCLKSTS bit 0 (1:
 * OSCCLK was found missing, the device runs from INTOSC1 with the PLL
 * bypassed), MCLKCLR bit 1 (write 1: clear, back to the selected source).
 * Offset 0x2E (after LOSPCP) as in TI's ClkCfgRegs layout; not in the
 * registers the review checked: check it on the board (docs/targets.md). */
#define CLK_MCDCR C28X_REG32(0x5D22Eu)
#define CLKSRC_XTALOFF (1u << 4)
#define PLLCTL_PLLEN (1u << 0)
#define PLLCTL_PLLCLKEN (1u << 1)
#define PLLSTS_LOCKS (1u << 0)
#define PLLSTS_SLIPS (1u << 1)
#define MCDCR_MCLKSTS (1u << 0)
#define MCDCR_MCLKCLR (1u << 1)

/* 3.15 CPU system registers: CpuSysRegs at 0x5D300 (peripheral clock gates) */
#define SYS_PCLKCR0 C28X_REG32(0x5D322u) /* CPUTIMER1 bit 4 */
#define SYS_PCLKCR7 C28X_REG32(0x5D330u) /* SCI_A bit 0 */

/* 2.12 flash wait states: Flash0CtrlRegs at 0x5F800 (change only from RAM) */
#define FLASH_FRDCNTL C28X_REG32(0x5F800u)       /* RWAIT[11:8] (reset 0xF: the most) */
#define FLASH_FRD_INTF_CTRL C28X_REG32(0x5F980u) /* PREFETCH_EN bit 0, DATA_CACHE_EN bit 1 */
/* Bank/pump power (2.12, Flash0CtrlRegs; offsets as in TI's FLASH_CTRL_REGS
 * layout, between FRDCNTL and FRD_INTF_CTRL; not in the registers the
 * review checked: check them on the board). */
#define FLASH_FBAC C28X_REG32(0x5F81Eu)       /* VREADST[7:0]: bank power-up delay */
#define FLASH_FBFALLBACK C28X_REG32(0x5F820u) /* BNKPWR0[1:0]: 3 = active */
#define FLASH_FPAC1 C28X_REG32(0x5F824u)      /* PMPPWR bit 0: 1 = active */
/* Flash0EccRegs at 0x5FB00: ECC_ENABLE[3:0], 0xA = on (reset value). */
#define FLASH_ECC_ENABLE C28X_REG32(0x5FB00u)
/* Flash pump semaphore (FlashPumpSemaphoreRegs.PUMPREQUEST): ownership in
 * bits 1:0 (2 = CPU1), written with the key 0x5A5A in bits 31:16.  Address,
 * key and value as TI's F2837x device support uses them, recalled: NOT
 * re-checked against SPRUHX5 here (docs/targets.md lists it for the first
 * flash). */
#define FLASH_PUMPREQUEST C28X_REG32(0x50024u)
#define PUMP_KEY 0x5A5A0000u
#define PUMP_CPU1 2u

/* 7.9 GPIO port C (GPIO64-95): GpioCtrlRegs at 0x7C00, port C block at +0x80 */
#define GPIO_GPCQSEL2 C28X_REG32(0x7C84u) /* 2 bits per pin 80-95: 3 = asynchronous */
#define GPIO_GPCMUX2 C28X_REG32(0x7C88u)  /* 2 bits per pin 80-95 */
#define GPIO_GPCPUD C28X_REG32(0x7C8Cu)   /* 1: pull-up disabled */
#define GPIO_GPCGMUX2 C28X_REG32(0x7CA2u) /* 2 bits per pin 80-95 (mux = GMUX*4 + MUX) */

/* 19.14 SCI registers: SciaRegs at 0x7200 */
#define SCIA_SCICCR C28X_REG16(0x7200u)   /* 0x07: 1 stop bit, no parity, 8 data bits */
#define SCIA_SCICTL1 C28X_REG16(0x7201u)  /* RXENA bit 0, TXENA bit 1, SWRESET bit 5 */
#define SCIA_SCIHBAUD C28X_REG16(0x7202u)
#define SCIA_SCILBAUD C28X_REG16(0x7203u)
#define SCIA_SCICTL2 C28X_REG16(0x7204u)  /* TXEMPTY bit 6, TXRDY bit 7 */
#define SCIA_SCITXBUF C28X_REG16(0x7209u)
/* 19.14 SCIRXST (+0x05): RXRDY bit 6 (a character is in SCIRXBUF), RXERROR
 * bit 7 (break, framing, overrun or parity error; cleared only by SWRESET);
 * SCIRXBUF (+0x07): received character in bits 7:0 (SAR), reading it
 * clears RXRDY. */
#define SCIA_SCIRXST C28X_REG16(0x7205u)
#define SCIA_SCIRXBUF C28X_REG16(0x7207u)
#define SCI_RXST_RXRDY (1u << 6)
#define SCI_RXST_RXERROR (1u << 7)
#define SCI_CTL1_SWRESET (1u << 5)
#define SCIA_SCIFFTX C28X_REG16(0x720Au)  /* SCIRST bit 15 (0: SCI held in reset), SCIFFENA bit 14 */
#define SCI_FFTX_SCIRST (1u << 15)
#define SCI_CTL2_TXRDY (1u << 7)
#define SCI_CTL2_TXEMPTY (1u << 6)

#endif /* C28X_REGS_H */
