/*
 * board.c -- LAUNCHXL-F28377S board layer: SYSPLL to 200 MHz, flash wait
 * states, FPU32 round-to-nearest, CpuTimer1 cycle counter, SCI-A console on
 * the XDS100v2 virtual COM port (GPIO84 = SCITXDA, GPIO85 = SCIRXDA, mux
 * position 5: LaunchPad user guide SPRUI25, data sheet SPRS881 GPIO mux
 * table).  The watchdog is disabled in codestart.c, before the C runtime
 * initialises memory.
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

#define XTAL_HZ 10000000u  /* LAUNCHXL-F28377S crystal X1 (SPRUI25) */
#define LSPCLK_HZ 50000000u /* SYSCLK / 4 (LOSPCP reset value) */
#define CONSOLE_BAUD 115200u

#if defined(__TI_COMPILER_VERSION__)
#pragma CODE_SECTION(flash_init, ".TI.ramfunc")
#endif
/* 2.12 (flash): 3 read wait states for SYSCLK 150-200 MHz (SPRS881), prefetch
 * and data cache on.  Runs from RAM: the flash is not read while it changes. */
static void flash_init(void)
{
    C28X_EALLOW();
    FLASH_FRDCNTL = (FLASH_FRDCNTL & ~(U32(0xFu) << 8)) | (U32(3u) << 8);
    FLASH_FRD_INTF_CTRL |= U32(3u);
    C28X_EDIS();
}

/* 3.7.6 (SYSPLL): XTAL source, multiplier 40 (400 MHz VCO), PLLSYSCLKDIV 1 (/2). */
static void clock_init(void)
{
    C28X_EALLOW();
    CLK_CLKSRCCTL1 = (CLK_CLKSRCCTL1 & ~(U32(1u) << 4)) & ~U32(3u); /* crystal on, source INTOSC2 meanwhile */
    CLK_CLKSRCCTL1 = (CLK_CLKSRCCTL1 & ~U32(3u)) | U32(1u);        /* OSCCLK = XTAL */
    CLK_SYSPLLCTL1 &= ~U32(2u);                                 /* PLLCLKEN = 0: bypass while locking */
    CLK_SYSCLKDIVSEL = U32(2u);                                 /* /4 while switching (no overshoot) */
    CLK_SYSPLLMULT = U32(40u);                                  /* IMULT 40, FMULT 0 */
    while ((CLK_SYSPLLSTS & U32(1u)) == U32(0u)) {                  /* LOCKS */
    }
    CLK_SYSPLLCTL1 |= U32(2u);                                  /* PLLCLKEN = 1 */
    CLK_SYSCLKDIVSEL = U32(1u);                                 /* 400 MHz / 2 = 200 MHz */
    SYS_PCLKCR0 |= (U32(1u) << 4);                              /* CPUTIMER1 clock */
    SYS_PCLKCR7 |= U32(1u);                                     /* SCI-A clock */
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

/* 7.x GPIO mux (GMUX first, then MUX) and 19.x SCI set-up, 115200 8N1. */
static void console_init(void)
{
    uint16_t brr = (uint16_t)(LSPCLK_HZ / (CONSOLE_BAUD * U32(8u)) - U32(1u));
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
    SCIA_SCIFFTX = 0u;                   /* FIFO off */
    SCIA_SCICTL1 = (uint16_t)((1u << 5) | (1u << 1) | 1u); /* release reset, TX and RX on */
}

void port_init(void)
{
    C28X_RNDF32_NEAREST();
    flash_init();
    clock_init();
    timer_init();
    console_init();
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
    console_puts("PORT tms320f28377 sysclk=200MHz(xtal10MHz*40/2) flash_ws=3 fpu32=round-to-nearest(RNDF32=1)"
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
