/*
 * c28x_sim.c -- host simulation of the registers the tms320f28377 port's
 * port_init touches (test_port_layout.py), for the board cl2000 cannot
 * build here.  board.c is compiled with -DMPC_C28X_TYPE_MODEL
 * -DMPC_C28X_HOST_SIM: every register access goes through c28x_sim_reg,
 * which returns a cell of this register file; EALLOW, EDIS, the RPT/NOP
 * delays and ESTOP0 come here as events.
 *
 * The effect of an access is applied at the next call (the access happens
 * after c28x_sim_reg returns): the log line "R addr value cycles" gives the
 * register's value after the access and the NOP cycles spent so far.  What
 * the simulated device does (only what the sequences need):
 *   - writing SYSPLLMULT turns the PLL on (PLLEN); LOCKS reads 1 while PLLEN
 *     is set, unless "pll-dead"; SLIPS reads 1 with "pll-slip";
 *   - "xtal-dead": with OSCCLKSRCSEL = XTAL the missing clock detect latches
 *     MCLKSTS; MCLKCLR clears it (it trips again while XTAL stays selected);
 *   - PUMPREQUEST takes ownership when written with key 0x5A5A, unless
 *     "pump-deny" (then it always reads 0);
 *   - SCICTL2 always reads TXRDY | TXEMPTY; each SCITXBUF write is a console
 *     character.
 * ESTOP0 (port_exit's halt) ends the program: it prints the console text
 * ("TX" and the octets in hex) and exits 0.
 *
 * Usage: c28x_sim [xtal-dead] [pll-dead] [pll-slip] [pump-deny]
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "c28x_regs.h"
#include "port.h"

#define NREG 96u
#define TXMAX 4096u

struct cell {
    uint32_t addr;
    uint32_t value;
};

static struct cell regs[NREG];
static unsigned nregs;
static struct cell *last;
static unsigned long long cycles;
static unsigned char tx[TXMAX];
static unsigned ntx;
static int xtal_dead, pll_dead, pll_slip, pump_deny;

static struct cell *cell_at(uint32_t addr)
{
    unsigned i;
    for (i = 0u; i < nregs; ++i) {
        if (regs[i].addr == addr) {
            return &regs[i];
        }
    }
    if (nregs == NREG) {
        fprintf(stderr, "c28x_sim: too many registers\n");
        exit(2);
    }
    regs[nregs].addr = addr;
    regs[nregs].value = 0u;
    return &regs[nregs++];
}

static uint32_t get(uint32_t addr)
{
    return cell_at(addr)->value;
}

static void set(uint32_t addr, uint32_t value)
{
    cell_at(addr)->value = value;
}

/* The device's response to the previous access, then the status bits. */
static void settle(void)
{
    if (last != NULL) {
        printf("R %05lx %08lx %llu\n", (unsigned long)last->addr, (unsigned long)last->value, cycles);
        switch (last->addr) {
        case 0x5D214u: /* SYSPLLMULT written: PLLEN */
            set(0x5D20Eu, get(0x5D20Eu) | 1u);
            break;
        case 0x5D22Eu: /* MCDCR: MCLKCLR */
            if ((last->value & 2u) != 0u) {
                last->value &= ~3u;
            }
            break;
        case 0x50024u: /* PUMPREQUEST */
            if (pump_deny) {
                last->value = 0u;
            } else if ((last->value >> 16) == 0x5A5Au) {
                last->value &= 3u;
            }
            break;
        case 0x7209u: /* SCITXBUF */
            if (ntx < TXMAX) {
                tx[ntx++] = (unsigned char)(last->value & 0xFFu);
            }
            break;
        default:
            break;
        }
        last = NULL;
    }
    if (xtal_dead && (get(0x5D208u) & 3u) == 1u) {
        set(0x5D22Eu, get(0x5D22Eu) | 1u);
    }
    set(0x5D216u, (((get(0x5D20Eu) & 1u) != 0u && !pll_dead) ? 1u : 0u) | (pll_slip ? 2u : 0u));
    set(0x7204u, 0xC0u);
}

volatile void *c28x_sim_reg(uint32_t addr)
{
    settle();
    last = cell_at(addr);
    return &last->value;
}

void c28x_sim_event(uint16_t what, uint16_t n)
{
    unsigned i;
    settle();
    if (what == 'N') {
        cycles += n;
        return;
    }
    printf("E %c %llu\n", (char)what, cycles);
    if (what == 'S') {
        printf("TX ");
        for (i = 0u; i < ntx; ++i) {
            printf("%02x", tx[i]);
        }
        printf("\n");
        exit(0);
    }
}

int main(int argc, char **argv)
{
    int i;
    for (i = 1; i < argc; ++i) {
        xtal_dead |= strcmp(argv[i], "xtal-dead") == 0;
        pll_dead |= strcmp(argv[i], "pll-dead") == 0;
        pll_slip |= strcmp(argv[i], "pll-slip") == 0;
        pump_deny |= strcmp(argv[i], "pump-deny") == 0;
    }
    set(0x5D208u, 0x10u);       /* CLKSRCCTL1 reset: XTALOFF, INTOSC2 */
    set(0x5D20Eu, 1u);          /* SYSPLLCTL1: PLLEN (boot ROM state unknown) */
    set(0x5D222u, 2u);          /* SYSCLKDIVSEL reset: /4 */
    set(0x5D22Cu, 2u);          /* LOSPCP reset: /4 */
    set(0x5F800u, 0xF00u);      /* FRDCNTL: RWAIT 15 */
    set(0x720Au, 0xA000u);      /* SCIFFTX reset */
    port_init();
    port_report();
    port_exit(0u);
    return 1; /* not reached: port_exit halts in ESTOP0 */
}
