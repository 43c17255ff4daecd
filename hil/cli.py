"""The ``mpcgen hil`` command: the serial HIL harness on codegen's command line.

codegen must never import hil, so the command registers itself: :data:`COMMAND`
is a :class:`codegen.cli.Command`, named in the entry-point group
``mpcgen.commands`` (pyproject ``[project.entry-points."mpcgen.commands"]``),
which the ``mpcgen`` console script (``codegen.cli:main``) loads.

    mpcgen hil CONFIG [--port URL | --board virtual|qemu-m7] --mode replay --states N --json FILE
    mpcgen hil CONFIG [--port URL | --board ...] --mode closed-loop --json FILE
    mpcgen hil CONFIG [--port URL | --board ...] --mode onboard [--decimation N] --json FILE

Exit codes as codegen.cli: 0 every state answered and equal, 1 mismatches,
lost states or a board error, 2 bad input (one line, checked before any long
run).
"""
from __future__ import annotations

import argparse
import contextlib
import sys
from collections.abc import Sequence
from typing import Any

from codegen import cli as base
from codegen import cliargs
from codegen.errors import MpcgenError, UsageError
from codegen.stages.training import with_trained_tables

__all__ = ["COMMAND", "cmd_hil", "main"]

MODES = ("replay", "closed-loop", "onboard")


def cmd_hil(args: argparse.Namespace) -> int:
    """Run the harness against one board."""
    import serial

    from codegen.topology import topology_of

    from .boards import BOARDS, VIRTUAL, open_board
    from .link import open_link
    from .qemu import QEMU_BOARD
    from .qemu import TIMEOUT_S as QEMU_TIMEOUT_S
    from .replay import replay
    from .schema import Schema
    from .session import Session
    from .states import replay_states

    if args.port is not None and args.board is not None:
        raise UsageError("--port and --board exclude each other: --port URL for a board on a serial port, "
                         f"--board {VIRTUAL} for the virtual board")
    if args.board not in (None, *BOARDS):
        raise UsageError(f"--board = {args.board!r}: the boards started by the harness are {', '.join(BOARDS)}; "
                         f"use --port URL for a board on a serial port")
    cliargs.at_least("--states", args.states, 1)
    cliargs.at_least("--retries", args.retries, 0)
    cliargs.at_least("--batch", args.batch, 1)
    cliargs.at_least("--baud", args.baud, 1)
    cliargs.at_least("--decimation", args.decimation, 1)
    if args.timeout is not None and not args.timeout > 0:
        raise UsageError(f"--timeout = {args.timeout}: must be a number of seconds > 0")
    cliargs.output_file("--json", args.json)
    log_path = cliargs.output_file("--log", args.log)
    model = base.load_model(args)
    log = base.progress_log(args.quiet)
    if args.check_log is not None:
        return _check_log(args, model, log)
    try:
        Schema.of(model).max_batch  # noqa: B018 -- the records must fit a frame
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    if args.port is not None:
        try:
            open_link(args.port, args.baud).close()  # fails here, before any long run
        except (serial.SerialException, OSError, ValueError) as exc:
            raise UsageError(f"--port = {args.port!r}: cannot open it ({exc})") from None
    if args.mode == "onboard":
        from codegen.simulator.driver import scenario_arrays

        from .onboard import profile_steps
        from .schema import MAX_STEPS
        steps = profile_steps(*scenario_arrays(model))
        if len(steps) > MAX_STEPS:
            raise UsageError(f"--mode onboard: the scenario has {len(steps)} speed/load steps, SETPOINTS takes at "
                             f"most {MAX_STEPS}")
    model = with_trained_tables(model, [model.controller.strategy], log)  # the board's config hash has them
    schema = Schema.of(model)
    tables = topology_of(model).derive(model)
    sets = replay_states(model, tables, args.states, args.seed) if args.mode == "replay" else {}
    try:
        with open_board(model, tables, args.port, board=args.board, baudrate=args.baud) as board_link, \
                contextlib.ExitStack() as stack:
            link: Any = board_link
            if log_path is not None:  # every octet both ways, for `mpcgen hil --check-log`
                from .exchange_log import LoggingLink

                header = {"config": str(args.config), "sets": args.sets, "config_hash": schema.config_hash,
                          "schema_hash": schema.schema_hash, "strategy": model.controller.strategy,
                          "board": args.port or args.board or VIRTUAL, "mode": args.mode}
                link = LoggingLink(board_link, stack.enter_context(open(log_path, "w")), header)
            # the emulated board: a long timeout (QEMU's slow UART input); else the defaults
            kw: dict[str, Any] = {"timeout_s": QEMU_TIMEOUT_S} if args.board == QEMU_BOARD else {}
            if args.timeout is not None:
                kw["timeout_s"] = args.timeout
            session = Session(link, schema, retries=args.retries, batch=args.batch, **kw)
            info = session.handshake()
            log(f"board {info.target}: config {info.config_hash}, schema {info.schema_hash}, clock "
                f"{info.core_clock_hz} Hz, cycles in {info.cycle_unit}, max batch {info.max_batch}")
            if args.mode == "replay":
                data = replay(session, model, tables, sets, show_progress=not args.quiet, log=log)
            elif args.mode == "onboard":
                return _mode_onboard(args, session, model, tables, log)
            else:
                return _loop_mode(args, session, model, tables, log)
    except serial.SerialException as exc:
        raise MpcgenError(f"serial link failed: {exc}") from None
    print(f"{data['states']} states  mismatches {data['mismatches']}  lost {data['lost']}  "
          f"{data['states_per_s']:,.0f} states/s  {data['octets_per_s']:,.0f} octets/s "
          f"(921600-baud UART: {data['uart_921600_octets_per_s']:,} octets/s)  {data['cycle_unit']} "
          f"min/median/p99/max {data['cycles_min']}/{data['cycles_median']}/{data['cycles_p99']}/{data['cycles_max']}")
    base.write_json(args.json, data)
    return base.EXIT_OK if data["mismatches"] == 0 and data["lost"] == 0 else base.EXIT_FAIL


def _check_log(args: argparse.Namespace, model: Any, log: Any) -> int:
    """``--check-log FILE``: re-verify a logged run offline (no board)."""
    from pathlib import Path

    from codegen.topology import topology_of

    from .exchange_log import check_log

    path = Path(args.check_log)
    if not path.is_file():
        raise UsageError(f"--check-log = {args.check_log!r}: no such file")
    model = with_trained_tables(model, [model.controller.strategy], log)
    try:
        data = check_log(model, topology_of(model).derive(model), path)
    except (ValueError, KeyError) as exc:
        raise UsageError(f"--check-log = {args.check_log!r}: {exc}") from None
    print(f"{data['results']} logged results ({data.get('distinct_states', 0)} states) re-verified offline: "
          f"mismatches {data['mismatches']}, results without a logged state {data['unmatched_results']}, "
          f"frames discarded (host->board {data['discarded_frames_out']}, board->host {data['discarded_frames_in']}), "
          f"malformed batches {data['bad_batches']}, malformed results {data['bad_results']}")
    base.write_json(args.json, data)
    # a malformed batch or result is a protocol fault: it fails the check (frames that do not decode
    # are counted only: the live run retried them)
    ok = data["mismatches"] == 0 and data["results"] > 0 and data["bad_batches"] == 0 and data["bad_results"] == 0
    return base.EXIT_OK if ok else base.EXIT_FAIL


def _loop_mode(args: argparse.Namespace, session: Any, model: Any, tables: Any, log: Any) -> int:
    """Mode closed-loop: run, print one line, write the JSON; the exit code."""
    from .closedloop import closed_loop, summary_line

    data = closed_loop(session, model, tables, show_progress=not args.quiet, log=log)
    print(summary_line(data))
    base.write_json(args.json, data)
    return base.EXIT_OK if data["ok"] else base.EXIT_FAIL


def _mode_onboard(args: argparse.Namespace, session: Any, model: Any, tables: Any, log: Any) -> int:
    """Mode onboard: run, print one line, write the JSON; the exit code."""
    from .onboard import onboard, summary_line

    data = onboard(session, model, tables, decimation=args.decimation, show_progress=not args.quiet, log=log)
    print(summary_line(data))
    base.write_json(args.json, data)
    return base.EXIT_OK if data["ok"] else base.EXIT_FAIL


def _arguments(h: argparse.ArgumentParser) -> None:
    """The options of ``mpcgen hil``."""
    base.add_config_args(h)
    where = h.add_mutually_exclusive_group()
    where.add_argument("--port", help="serial URL of the board: a device (/dev/ttyACM0), a pseudo-terminal or "
                                      "socket://HOST:PORT")
    where.add_argument("--board", help="board started by the harness: virtual (the default), the host port built "
                                       "with the protocol; qemu-m7, the emulated Cortex-M7 in QEMU (cycles in "
                                       "instructions)")
    h.add_argument("--baud", type=int, default=921600,
                   help="baud rate of a serial device given with --port (default 921600)")
    h.add_argument("--mode", choices=MODES, default="replay",
                   help="replay: recorded closed-loop, random and adversarial states compared bit for bit; "
                        "closed-loop: the host simulates the plant, the board decides every period (the "
                        "decisions must equal mpcgen simulate's); onboard: the board runs a float32 plant and "
                        "the controller at full rate on the scenario's speed/load steps, its telemetry metrics "
                        "are compared with mpcgen simulate's within a stated tolerance")
    h.add_argument("--decimation", type=int, default=1,
                   help="mode onboard: one telemetry sample every N periods (default 1)")
    h.add_argument("--states", type=int, default=6000,
                   help="replay: states in all, shared between the recorded closed-loop run, random and "
                        "adversarial states (default 6000)")
    h.add_argument("--log", help="write every octet exchanged with the board to FILE (JSON lines)")
    h.add_argument("--check-log", metavar="FILE",
                   help="re-verify a log written with --log offline against the reference (no board)")
    h.add_argument("--seed", type=int, default=1, help="seed of the random states (default 1)")
    h.add_argument("--timeout", type=float, default=None,
                   help="seconds before an unanswered frame is sent again (default 0.5; qemu-m7: 10)")
    h.add_argument("--retries", type=int, default=3, help="times a state is sent again before it counts as lost")
    h.add_argument("--batch", type=int, default=16, help="states per BATCH frame (at most the board's max batch)")
    h.add_argument("--json", help="write the summary as JSON")


#: ``mpcgen hil`` (the entry point ``hil = "hil.cli:COMMAND"`` of the group ``mpcgen.commands``)
COMMAND = base.Command("hil", "run the controller on a board over a serial port, bit for bit against the reference",
                       _arguments, cmd_hil)


def main(argv: Sequence[str] | None = None) -> int:
    """``mpcgen`` with ``argv`` (``codegen.cli.main``: every command, ``hil`` included)."""
    return base.main(argv)


if __name__ == "__main__":
    sys.exit(main())
