"""The ``mpcgen hil`` command: the serial HIL harness on codegen's command line.

codegen must never import hil, so the command registers itself: :data:`COMMAND`
is a :class:`codegen.cli.Command`, named in the entry-point group
``mpcgen.commands`` (pyproject ``[project.entry-points."mpcgen.commands"]``),
which the ``mpcgen`` console script (``codegen.cli:main``) loads.

    mpcgen hil CONFIG [--port URL | --board virtual|qemu-m7] --mode replay --states N --json FILE
    mpcgen hil CONFIG [--port URL | --board ...] --resume FILE --json FILE   (finish an interrupted replay)
    mpcgen hil CONFIG [--port URL | --board ...] --mode closed-loop --json FILE
    mpcgen hil CONFIG [--port URL | --board ...] --mode onboard [--decimation N] --json FILE

Exit codes as codegen.cli: 0 every state answered and equal, 1 mismatches,
lost states or a board error, 2 bad input (one line, checked before any long
run).

A link that fails mid-run (hang-up, EIO, a closed socket, a broken pipe) or
Ctrl-C ends the run with one line naming the port and the error, exit 1;
the JSON (``--json``, else a file named in that line) keeps every state
answered so far with ``complete: false`` and the unanswered ones, and
``--resume`` with that JSON finishes them.
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
#: --states and --seed when neither they nor a --resume file give them
DEFAULT_STATES, DEFAULT_SEED = 6000, 1


def _resume_source(args: argparse.Namespace) -> dict[str, Any] | None:
    """``--resume FILE`` read and checked against the options (UsageError); fills --states and --seed."""
    from .replay import load_resume

    if args.resume is None:
        args.states = DEFAULT_STATES if args.states is None else args.states
        args.seed = DEFAULT_SEED if args.seed is None else args.seed
        return None
    if args.mode != "replay":
        raise UsageError(f"--resume finishes an interrupted replay; --mode {args.mode} starts over")
    try:
        doc = load_resume(args.resume)
    except ValueError as exc:
        raise UsageError(f"--resume = {args.resume!r}: {exc}") from None
    for option, name, value in (("--states", "states", doc["states"]), ("--seed", "seed", doc["resume"]["seed"])):
        given = getattr(args, name)
        if given is not None and given != value:
            raise UsageError(f"{option} = {given}: the run in --resume = {args.resume!r} has {value}; "
                             f"leave {option} out (the file gives it)")
        setattr(args, name, value)
    return doc


def _handshake_line(info: Any) -> str:
    """What the board says about itself; a clock only where its counts are clock cycles."""
    from .progress import timing_label

    clock = f", clock {info.core_clock_hz} Hz" if info.cycle_unit == "cycles" and info.core_clock_hz > 0 else ""
    return (f"board {info.target}: config {info.config_hash}, schema {info.schema_hash}{clock}, timings in "
            f"{timing_label(info.cycle_unit)}, max batch {info.max_batch}")


def _failure_line(failure: str, data: dict[str, Any], json_path: str) -> str:
    """The one line of a run the link or Ctrl-C ended: the error, what was kept and how to finish."""
    return (f"{failure}: {data['answered']} of {data['states']} states answered and kept in {json_path} "
            f"(complete: false, {data['unanswered']} unanswered); finish them with --resume {json_path}")


def cmd_hil(args: argparse.Namespace) -> int:
    """Run the harness against one board."""
    import serial

    from codegen.topology import topology_of

    from .boards import BOARDS, VIRTUAL, open_board
    from .exchange_log import finish_log
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
    if args.states is not None:
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
        if args.resume is not None:
            raise UsageError("--check-log and --resume exclude each other")
        return _check_log(args, model, log)
    resume = _resume_source(args)
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
    evidence = generated_c(model, args.board)
    prior = None
    if resume is not None:
        import numpy as np

        from .replay import prior_of
        try:
            prior = prior_of(resume, args.resume, schema, np.concatenate(list(sets.values())))
        except ValueError as exc:
            raise UsageError(f"--resume = {args.resume!r}: {exc}") from None
    try:
        with open_board(model, tables, args.port, board=args.board, baudrate=args.baud) as board_link, \
                contextlib.ExitStack() as stack:
            link: Any = board_link
            if log_path is not None:  # every octet both ways, for `mpcgen hil --check-log`
                from .exchange_log import LoggingLink

                header = {"config": str(args.config), "sets": args.sets, "config_hash": schema.config_hash,
                          "schema_hash": schema.schema_hash, "strategy": model.controller.strategy,
                          "board": args.port or args.board or VIRTUAL, "mode": args.mode, **evidence}
                # the log's end record: the run's summary (finish_log below), or the exception that ended it
                link = stack.enter_context(LoggingLink(board_link, stack.enter_context(open(log_path, "w")), header))
            # the emulated board: a long timeout (QEMU's slow UART input); else the defaults
            kw: dict[str, Any] = {"timeout_s": QEMU_TIMEOUT_S} if args.board == QEMU_BOARD else {}
            if args.timeout is not None:
                kw["timeout_s"] = args.timeout
            session = Session(link, schema, retries=args.retries, batch=args.batch, **kw)
            info = session.handshake()
            log(_handshake_line(info))
            if args.mode == "replay":
                data = {**replay(session, model, tables, sets, show_progress=not args.quiet, log=log,
                                 seed=args.seed, prior=prior), **evidence}
                finish_log(link, data)
            elif args.mode == "onboard":
                return _mode_onboard(args, session, model, tables, log, evidence)
            else:
                return _loop_mode(args, session, model, tables, log, evidence)
    except serial.SerialException as exc:
        raise MpcgenError(f"serial link failed: {exc}") from None
    return _replay_done(args, data, schema.config_hash)


def _replay_done(args: argparse.Namespace, data: dict[str, Any], config_hash: str) -> int:
    """Print the replay's line, write its JSON (an incomplete run's too, --json or not); the exit code."""
    from .replay import summary_line

    print(summary_line(data))
    path = args.json
    if path is None and not data["complete"]:  # what was answered is never thrown away
        path = f"hil-{data['config']}-{config_hash}.partial.json"
    try:
        base.write_json(path, data)
    except OSError as exc:
        raise MpcgenError(f"cannot write the JSON {path}: {exc}") from None
    if data["failure"] is not None:
        raise MpcgenError(_failure_line(data["failure"], data, str(path)))
    ok = data["mismatches"] == 0 and data["lost"] == 0 and data["complete"]
    return base.EXIT_OK if ok else base.EXIT_FAIL


def _check_log(args: argparse.Namespace, model: Any, log: Any) -> int:
    """``--check-log FILE``: re-verify a logged run offline (no board): its digests, completeness, frames,
    sequence numbers, hashes, and every result bit for bit; exit 1 with the first problem's line."""
    from pathlib import Path

    from codegen.topology import topology_of

    from .log_check import LogRefused, check_log, summary_line, truncation_line

    path = Path(args.check_log)
    if not path.is_file():
        raise UsageError(f"--check-log = {args.check_log!r}: no such file")
    model = with_trained_tables(model, [model.controller.strategy], log)
    try:
        data = check_log(model, topology_of(model).derive(model), path, {"config": args.config, "sets": args.sets})
    except (LogRefused, OSError) as exc:
        raise UsageError(f"--check-log = {args.check_log!r}: {exc}") from None
    base.write_json(args.json, data)
    if data["truncated_at_line"] is not None:  # bad input: one line, what the lines before the cut gave
        raise UsageError(f"--check-log = {args.check_log!r}: {truncation_line(data)}")
    print(summary_line(data))
    return base.EXIT_OK if data["ok"] else base.EXIT_FAIL


def generated_c(model: Any, board: str | None) -> dict[str, str]:
    """The hash of the generated C the board runs (``codegen.manifest.c_hash``: the same value as the
    manifest ``mpcgen generate`` writes for that target) and the target it is for: the host build on the
    virtual board, the firmware board's profile under QEMU, the config's ``target.name`` on a port."""
    from codegen.manifest import c_hash
    from codegen.stages.firmware import BOARDS

    from .boards import QEMU_BOARD

    target = {None: model.target, QEMU_BOARD: BOARDS[QEMU_BOARD].profile}.get(board, "host")
    return {"c_hash": c_hash(model, target), "c_hash_target": target}


def _loop_mode(args: argparse.Namespace, session: Any, model: Any, tables: Any, log: Any,
               evidence: dict[str, str]) -> int:
    """Mode closed-loop: run, print one line, write the JSON; the exit code."""
    from .closedloop import closed_loop, summary_line
    from .exchange_log import finish_log
    from .progress import rename_timing_keys, wire_note

    data = closed_loop(session, model, tables, show_progress=not args.quiet, log=log)
    data["wire"]["handshake_retries"] = session.handshake_retries
    print(summary_line(data) + wire_note(data["wire"]))
    data = {**rename_timing_keys(data, data["cycle_unit"]), **evidence}  # closedloop.py names them cycles_*
    data["failure"] = session.failure
    finish_log(session.link, data)
    base.write_json(args.json, data)
    if session.failure is not None:
        raise MpcgenError(f"{session.failure}: the closed loop stopped at period {data['lost_at']} of "
                          f"{data['periods']}" + (f"; the periods run are in {args.json}" if args.json else ""))
    return base.EXIT_OK if data["ok"] else base.EXIT_FAIL


def _mode_onboard(args: argparse.Namespace, session: Any, model: Any, tables: Any, log: Any,
                  evidence: dict[str, str]) -> int:
    """Mode onboard: run, print one line, write the JSON; the exit code."""
    from .exchange_log import finish_log
    from .onboard import onboard, summary_line

    data = {**onboard(session, model, tables, decimation=args.decimation, show_progress=not args.quiet, log=log),
            **evidence}
    finish_log(session.link, data)
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
                                       "with the protocol; qemu-m7, the emulated Cortex-M7 in QEMU (timings in "
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
    h.add_argument("--states", type=cliargs.count, default=None,
                   help="replay: states in all, shared between the recorded closed-loop run, random and "
                        f"adversarial states (default {DEFAULT_STATES}; with --resume, the file's)")
    h.add_argument("--resume", metavar="JSON",
                   help="replay: finish an interrupted run (the link failed, Ctrl-C): give the JSON that run "
                        "wrote (its --json, or the file its error line names; not a --log), with the same config "
                        "and overrides; only the states it did not answer are sent, and the JSON written "
                        "is that of the whole run")
    h.add_argument("--log", help="write every octet exchanged with the board to FILE (JSON lines)")
    h.add_argument("--check-log", metavar="FILE",
                   help="re-verify a log written with --log offline against the reference (no board)")
    h.add_argument("--seed", type=int, default=None,
                   help=f"seed of the random states (default {DEFAULT_SEED}; with --resume, the file's)")
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
