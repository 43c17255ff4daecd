/*
 * main.c -- the firmware's work, the same on every board: HELLO, the port's
 * report, the cycle-measurement overhead, every embedded test set, RESULT,
 * exit code (0: every state of every set bit-identical to the reference).
 * Serial protocol builds (MPC_HIL defined) serve the HIL protocol instead
 * (hil_proto.h).
 */
#include <stdint.h>

#if defined(MPC_HIL)

#include "hil_proto.h"
#include "port.h"

int main(void)
{
    port_init();
    hil_serve();
    return 0;
}

#else

#include "console.h"
#include "mpc_runtime.h"
#include "port.h"
#include "selftest.h"

/* Equal C strings (no library call, no byte pointer arithmetic on records). */
static uint16_t same_text(const char *a, const char *b)
{
    while (*a != '\0' && *a == *b) {
        ++a;
        ++b;
    }
    return (uint16_t)(*a == *b);
}

int main(void)
{
    uint32_t failures = 0u;
    uint32_t overhead;
    uint16_t s;

    port_init();
    console_puts("HELLO mpcgen");
    console_kv_str("board", PORT_BOARD);
    console_kv_str("config", MPC_CONFIG_HASH);
    console_kv_str("strategy", MPC_DATA_STRATEGY);
    console_kv_u32("clock_hz", (uint32_t)PORT_CORE_CLOCK_HZ);
    console_kv_str("cycle_unit", PORT_CYCLE_UNIT);
    console_kv_u32("sets", (uint32_t)MPC_N_TESTSETS);
    console_eol();
    port_report();
    if (same_text(MPC_CONFIG_HASH, MPC_DATA_CONFIG_HASH) == 0u) {
        console_puts("ERROR test data built for config " MPC_DATA_CONFIG_HASH ", controller is " MPC_CONFIG_HASH);
        console_eol();
        failures = 1u;
    }
    overhead = mpc_overhead(16u);
    console_puts("OVERHEAD");
    console_kv_u32("cycles", overhead);
    console_kv_str("unit", PORT_CYCLE_UNIT);
    console_eol();
    for (s = 0u; s < (uint16_t)MPC_N_TESTSETS; ++s) {
        failures += mpc_selftest_run(&mpc_testsets[s], overhead);
    }
    console_puts((failures == 0u) ? "RESULT PASS" : "RESULT FAIL");
    console_kv_u32("failures", failures);
    console_eol();
    port_exit((uint16_t)((failures == 0u) ? 0u : 1u));
    return 0;
}

#endif /* MPC_HIL */
