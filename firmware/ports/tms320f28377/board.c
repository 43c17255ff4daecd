/*
 * board.c -- LAUNCHXL-F28377S board layer: flash wait states and power,
 * SYSPLL to 200 MHz, FPU32 round-to-nearest, CpuTimer1 cycle counter, SCI-A
 * console on the XDS100v2 virtual COM port (GPIO84 = SCITXDA, GPIO85 =
 * SCIRXDA, mux position 5: LaunchPad user guide SPRUI25, data sheet SPRS881
 * GPIO mux table).  The watchdog is disabled before the C runtime starts
 * (codestart.c), as TI's CodeStartBranch does by default.
 *
 * The sequences follow TI's F2837xS device support (InitFlash, InitSysPll,
 * the crystal selection of its driverlib, the non-FIFO SCI set-up), from
 * their documented steps; each deviation is commented where it is.  Every
 * wait on a status bit is bounded.  A failure (no flash pump, PLL never
 * locked or slipping, no usable oscillator) leaves the device on a clock
 * whose rate is known, so the console works: port_init prints ERROR lines
 * and stops with EXIT code=4 (docs/targets.md, first flash).  A crystal
 * that does not start is not a failure: the PLL then runs from INTOSC2 and
 * the PORT line says so (as the STM32H743 port falls back to HSI).
 *
 * FPU32 (targets.md, numerics.md): RNDF32 = 1 selects round to nearest;
 * denormal results and operands are flushed to zero by the hardware, which
 * the Python reference does not model: a state whose float path meets a
 * denormal may mismatch (the self-test reports it).
 */
#include <limits.h>
#include <stdint.h>

#include "c28x_regs.h"
#include "console.h"
#include "mpc_binding.h"
#include "mpc_values.h"
#include "port.h"

/* The records have the interface's layout in bits on every target (numpy
 * INPUT_DTYPE / OUTPUT_DTYPE, mpc_values.h), whatever CHAR_BIT is. */
#define C28X_CHECK(name, cond) typedef int name[(cond) ? 1 : -1]
C28X_CHECK(c28x_input_layout, sizeof(mpc_input_t) * CHAR_BIT == MPC_INPUT_BITS);
C28X_CHECK(c28x_output_layout, sizeof(mpc_output_t) * CHAR_BIT == MPC_OUTPUT_BITS);
C28X_CHECK(c28x_float32, sizeof(float) * CHAR_BIT == 32u);
C28X_CHECK(c28x_uint16, sizeof(uint16_t) * CHAR_BIT == 16u);

/* 32-bit unsigned constant: `long` is 32 bits on C28x but 64 on an LP64 host. */
#define U32(x) ((uint32_t)(x))

#define OSC_HZ 10000000u      /* INTOSC2 and the LAUNCHXL-F28377S crystal X1 (SPRUI25): 10 MHz */
#define SYSCLK_HZ 200000000u  /* OSCCLK x 40 / 2 */
#define CONSOLE_BAUD 115200u

/* Bounded waits count spins of C28X_NOP100 (at least 100 SYSCLK cycles
 * each).  clock_init runs with SYSCLK = OSCCLK / 1 = 10 MHz until the
 * switch to the PLL, so SPINS_US(us) spins last at least `us` microseconds
 * (flash wait states only make them longer). */
#define SPINS_US(us) (((uint32_t)(us) * U32(OSC_HZ / 1000000u) + U32(99u)) / U32(100u))
#define XTAL_START_US 1000u  /* TI: 1 ms for the crystal to power up before it is selected */
#define MCD_SETTLE_US 1000u  /* after selecting it, before reading the missing-clock status (our choice) */
#define MCD_RETRIES 4u       /* TI: clear the missing-clock detect and wait again, up to 4 times */
#define PLL_LOCKS 5u         /* TI: lock the PLL five times before using it */
#define PLL_LOCK_US 10000u   /* per lock: LOCKS must set within 10 ms (the lock takes well under 1 ms) */
#define PUMP_SPINS 1000u     /* flash pump semaphore: tries (one CPU here: granted at once) */

/* What failed (port_init reports each on its own ERROR line). */
#define FAIL_FLASH_PUMP 1u /* pump semaphore not granted: flash left at reset wait states (the most) */
#define FAIL_OSC 2u        /* missing clock detect still set after falling back to INTOSC2 */
#define FAIL_PLL 4u        /* no lock within PLL_LOCK_US, or SLIPS set: PLL off, SYSCLK = OSCCLK */

static uint16_t fail;
static uint16_t xtal_ok;
static uint32_t lspclk_hz;

#if defined(__TI_COMPILER_VERSION__)
#pragma CODE_SECTION(flash_init, ".TI.ramfunc")
#endif
/* TI's InitFlash order (SPRUHX5 2.12; wait states: SPRS881, 3 for SYSCLK
 * 150-200 MHz): claim the flash pump, bank power-up delay VREADST = 0x14,
 * pump and bank active, cache and prefetch off while RWAIT changes, then
 * on, ECC on, and an 8-cycle pipeline flush so the last write completes
 * before the return.  Runs from RAM (.TI.ramfunc, copied by the C runtime's
 * BINIT table): the flash is not read while it changes, and the wait below
 * calls nothing that lives in flash.  The pump is kept (TI releases it only
 * for another master; the F28377S has one CPU). */
static uint16_t flash_init(void)
{
    uint16_t spins = PUMP_SPINS;
    C28X_EALLOW();
    while ((FLASH_PUMPREQUEST & U32(3u)) != U32(PUMP_CPU1)) {
        if (spins == 0u) {
            C28X_EDIS();
            return 0u;
        }
        FLASH_PUMPREQUEST = U32(PUMP_KEY) | U32(PUMP_CPU1);
        --spins;
        C28X_NOP100();
    }
    FLASH_FBAC = (FLASH_FBAC & ~U32(0xFFu)) | U32(0x14u);
    FLASH_FPAC1 |= U32(1u);
    FLASH_FBFALLBACK = (FLASH_FBFALLBACK & ~U32(3u)) | U32(3u);
    FLASH_FRD_INTF_CTRL &= ~U32(3u);
    FLASH_FRDCNTL = (FLASH_FRDCNTL & ~(U32(0xFu) << 8)) | (U32(3u) << 8);
    FLASH_FRD_INTF_CTRL |= U32(3u);
    FLASH_ECC_ENABLE = U32(0xAu);
    C28X_EDIS();
    C28X_NOP8();
    return 1u;
}

static void spin(uint32_t n)
{
    while (n > U32(0u)) {
        C28X_NOP100();
        --n;
    }
}

/* Wait until (reg & mask) == want, at most n spins; 1 if it happened. */
static uint16_t spin_until(volatile uint32_t *reg, uint32_t mask, uint32_t want, uint32_t n)
{
    for (;;) {
        if ((*reg & mask) == want) {
            return 1u;
        }
        if (n == U32(0u)) {
            return 0u;
        }
        C28X_NOP100();
        --n;
    }
}

/* The crystal as OSCCLK, following TI's driverlib order: crystal on, 1 ms,
 * select it, then check the missing clock detect and, while it has
 * tripped, clear it and wait again, up to MCD_RETRIES times.  TI also waits
 * for the X1 counter (X1CNT) to saturate; not done here (that register is
 * not among this port's checked facts): the fixed 1 ms waits stand in.
 * If the crystal never runs, TI's driver stops (ESTOP0); here OSCCLK goes
 * back to INTOSC2 and the board carries on (PORT line: osc=intosc2).
 * Returns 1 if OSCCLK is the crystal; sets FAIL_OSC if no oscillator is
 * clean afterwards (then OSCCLK is INTOSC1, still 10 MHz). */
static uint16_t xtal_select(void)
{
    uint16_t tries = 0u;
    CLK_CLKSRCCTL1 &= ~U32(CLKSRC_XTALOFF);
    spin(SPINS_US(XTAL_START_US));
    CLK_CLKSRCCTL1 = (CLK_CLKSRCCTL1 & ~U32(3u)) | U32(1u);
    for (;;) {
        spin(SPINS_US(MCD_SETTLE_US));
        if ((CLK_MCDCR & U32(MCDCR_MCLKSTS)) == U32(0u)) {
            return 1u;
        }
        if (tries == MCD_RETRIES) {
            break;
        }
        ++tries;
        CLK_MCDCR |= U32(MCDCR_MCLKCLR);
        spin(SPINS_US(XTAL_START_US));
    }
    CLK_CLKSRCCTL1 &= ~U32(3u); /* OSCCLKSRCSEL = INTOSC2, then clear the detect: back to it */
    CLK_MCDCR |= U32(MCDCR_MCLKCLR);
    CLK_CLKSRCCTL1 |= U32(CLKSRC_XTALOFF);
    spin(SPINS_US(MCD_SETTLE_US));
    if ((CLK_MCDCR & U32(MCDCR_MCLKSTS)) != U32(0u)) {
        fail |= FAIL_OSC;
    }
    return 0u;
}

/* TI's InitSysPll (SPRUHX5 3.7.6 SYSPLL): PLL bypassed and SYSCLK divider
 * /1 first, oscillator, then the PLL locked PLL_LOCKS times (each: PLLEN
 * off, at least 60 OSCCLK cycles, multiplier written, which turns the PLL
 * on and starts a lock; wait for LOCKS), the last lock checked (LOCKS set,
 * SLIPS clear), divider one step slower (/4: 100 MHz, limits the current
 * step), PLLCLKEN, 21 cycles, 201 cycles for the regulator, then /2:
 * 200 MHz.  Deviations, with their reason:
 *  - the oscillator is selected after the bypass (TI: before): the waits
 *    count SYSCLK cycles, which needs SYSCLK = OSCCLK / 1 first, and the PLL
 *    is relocked after the source changes anyway;
 *  - each lock wait is bounded (TI: unbounded); a failed or slipping last
 *    lock leaves the PLL off and SYSCLK at OSCCLK (FAIL_PLL);
 *  - TI arms the watchdog (with the SYSDBGCTL flag) around PLLCLKEN so a
 *    hang there resets the device: not done, this port has no reset-cause
 *    handling and that flag register is not among its checked facts. */
static void clock_init(void)
{
    uint16_t i, locked = 0u;
    C28X_EALLOW();
    CLK_SYSPLLCTL1 &= ~U32(PLLCTL_PLLCLKEN);
    C28X_NOP21();
    CLK_SYSCLKDIVSEL = U32(0u);
    xtal_ok = xtal_select();
    if ((fail & FAIL_OSC) == 0u) {
        for (i = 0u; i < PLL_LOCKS; ++i) {
            CLK_SYSPLLCTL1 &= ~U32(PLLCTL_PLLEN);
            C28X_NOP100();
            CLK_SYSPLLMULT = U32(40u); /* IMULT 40, FMULT 0: VCO 400 MHz */
            locked = spin_until(&CLK_SYSPLLSTS, U32(PLLSTS_LOCKS), U32(PLLSTS_LOCKS), SPINS_US(PLL_LOCK_US));
        }
    }
    if (locked != 0u && (CLK_SYSPLLSTS & U32(PLLSTS_SLIPS)) == U32(0u)) {
        CLK_SYSCLKDIVSEL = U32(2u);
        CLK_SYSPLLCTL1 |= U32(PLLCTL_PLLCLKEN);
        C28X_NOP21();
        C28X_NOP201();
        CLK_SYSCLKDIVSEL = U32(1u);
        lspclk_hz = SYSCLK_HZ / U32(4u); /* LOSPCP reset value: SYSCLK / 4 */
    } else {
        CLK_SYSPLLCTL1 &= ~U32(PLLCTL_PLLEN);
        CLK_LOSPCP = U32(0u); /* LSPCLK = SYSCLK = 10 MHz: the console still reaches 115200 baud */
        lspclk_hz = OSC_HZ;
        if ((fail & FAIL_OSC) == 0u) {
            fail |= FAIL_PLL;
        }
    }
    SYS_PCLKCR0 |= (U32(1u) << 4); /* CPUTIMER1 clock */
    SYS_PCLKCR7 |= U32(1u);        /* SCI-A clock */
    C28X_EDIS();
}

/* 3.14: CpuTimer1 free running at SYSCLK over 32 bits. */
static void timer_init(void)
{
    CPUTIMER1_TCR = (uint16_t)TCR_TSS;
    CPUTIMER1_PRD = U32(0xFFFFFFFFu);
    CPUTIMER1_TPR = 0u;
    CPUTIMER1_TPRH = 0u;
    CPUTIMER1_TCR = (uint16_t)(TCR_TSS | TCR_TRB);
    CPUTIMER1_TCR = (uint16_t)TCR_FREE; /* TSS = 0: run; FREE: keep running at a breakpoint */
}

/* 7.x GPIO mux (GMUX first, then MUX) and 19.x SCI set-up, 115200 8N1 from
 * LSPCLK, TI's non-FIFO order: held in reset while configured, SCIFFTX =
 * 0x8000 (SCIRST set: the SCI out of reset; FIFO enhancements off), then
 * released. */
static void console_init(void)
{
    uint16_t brr = (uint16_t)((lspclk_hz + CONSOLE_BAUD * U32(4u)) / (CONSOLE_BAUD * U32(8u)) - U32(1u));
    C28X_EALLOW();
    GPIO_GPCPUD &= ~(U32(3u) << 20);                                 /* pull-ups on GPIO84/85 */
    GPIO_GPCQSEL2 = (GPIO_GPCQSEL2 & ~(U32(3u) << 10)) | (U32(3u) << 10); /* GPIO85: asynchronous input */
    GPIO_GPCMUX2 &= ~(U32(0xFu) << 8);
    GPIO_GPCGMUX2 = (GPIO_GPCGMUX2 & ~(U32(0xFu) << 8)) | (U32(0x5u) << 8); /* GMUX = 1 for GPIO84, 85 */
    GPIO_GPCMUX2 |= (U32(0x5u) << 8);                                /* MUX = 1: position 5 = SCIA */
    C28X_EDIS();
    SCIA_SCICTL1 = 0u;                   /* SWRESET = 0: hold in reset */
    SCIA_SCICCR = 0x0007u;
    SCIA_SCIHBAUD = (uint16_t)(brr >> 8);
    SCIA_SCILBAUD = (uint16_t)(brr & 0xFFu);
    SCIA_SCIFFTX = (uint16_t)SCI_FFTX_SCIRST;
    SCIA_SCICTL1 = (uint16_t)((1u << 5) | (1u << 1) | 1u); /* release reset, TX and RX on */
}

static void report_failure(uint16_t flag, const char *stage, const char *state)
{
    if ((fail & flag) != 0u) {
        console_puts("ERROR port_init");
        console_kv_str("board", PORT_BOARD);
        console_kv_str("stage", stage);
        console_kv_str("state", state);
        console_eol();
    }
}

void port_init(void)
{
    C28X_RNDF32_NEAREST();
    if (flash_init() == 0u) {
        fail |= FAIL_FLASH_PUMP;
    }
    clock_init();
    timer_init();
    console_init();
    if (fail != 0u) {
        report_failure(FAIL_FLASH_PUMP, "flash-pump-semaphore", "flash-at-reset-wait-states");
        report_failure(FAIL_OSC, "missing-clock-detect", "oscclk-intosc1-pll-off-sysclk-10MHz");
        report_failure(FAIL_PLL, "pll-lock", "pll-off-sysclk-10MHz");
        port_exit(4u);
    }
}

#if defined(MPC_HIL)
/* Polled receive (SPRUHX5 19.14 SCIRXST/SCIRXBUF, FIFO off): one 16-bit
 * word per character, its low 8 bits.  A receive error is cleared by
 * pulsing SWRESET (the lost octets show as a bad frame the host sends again). */
uint16_t port_read(uint16_t *octets, uint16_t max)
{
    uint16_t n = 0u;
    if ((SCIA_SCIRXST & SCI_RXST_RXERROR) != 0u) {
        SCIA_SCICTL1 = (uint16_t)(SCIA_SCICTL1 & (uint16_t)~SCI_CTL1_SWRESET);
        SCIA_SCICTL1 = (uint16_t)(SCIA_SCICTL1 | SCI_CTL1_SWRESET);
    }
    while (n < max && (SCIA_SCIRXST & SCI_RXST_RXRDY) != 0u) {
        octets[n] = (uint16_t)(SCIA_SCIRXBUF & 0xFFu);
        ++n;
    }
    return n;
}
#endif

void port_putc(uint16_t c)
{
    while ((SCIA_SCICTL2 & SCI_CTL2_TXRDY) == 0u) {
    }
    SCIA_SCITXBUF = (uint16_t)(c & 0xFFu);
}

uint32_t port_cycles(void)
{
    return ~CPUTIMER1_TIM;
}

void port_report(void)
{
    console_puts("PORT tms320f28377 sysclk=200MHz(osc10MHz*40/2)");
    console_kv_str("osc", (xtal_ok != 0u) ? "xtal" : "intosc2(xtal-did-not-start)");
    console_puts(" flash_ws=3 fpu32=round-to-nearest(RNDF32=1)"
                 " denormals=flushed-to-zero cycles=cputimer1 console=scia(gpio84/85)");
    console_eol();
}

void port_exit(uint16_t code)
{
    console_puts("EXIT");
    console_kv_u32("code", code);
    console_eol();
    while ((SCIA_SCICTL2 & SCI_CTL2_TXEMPTY) == 0u) {
    }
    for (;;) {
        C28X_ESTOP();
    }
}
