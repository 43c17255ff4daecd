"""``mpcgen`` command line: generate, verify, simulate, tables, bench, firmware, sweep, tune, study, report,
evidence, and the commands other packages register (``hil``).

Every command is a :class:`Command`: its name, one-line help, a function adding its options and the
function that runs it.  codegen's own are :data:`COMMANDS`; another package adds one through the
entry-point group :data:`ENTRY_POINT_GROUP` (``mpcgen.commands``) of its distribution, an entry point
``name = "module:ATTRIBUTE"`` naming a :class:`Command` of that name (pyproject
``[project.entry-points."mpcgen.commands"]``), so that codegen never imports it.  The helpers such a
command needs are public here: :func:`add_config_args`, :func:`load_model`, :func:`progress_log`,
:func:`write_json` and the exit codes.

Exit codes: 0 success; 1 the job ran and failed (mismatches, build failure);
2 bad input (config, arguments) -- one line on stderr, no traceback.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from importlib.metadata import entry_points
from pathlib import Path
from typing import TYPE_CHECKING, Any

from codegen import __version__, cliargs
from codegen.errors import ConfigError, MpcgenError, UsageError
from codegen.model import TARGETS, Model
from codegen.outputs import write_atomic

if TYPE_CHECKING:  # the heavy modules (numpy, the compilers' glue) load when a command runs, not at start-up
    from codegen.topology import Topology

__all__ = ["Command", "COMMANDS", "ENTRY_POINT_GROUP", "EXIT_OK", "EXIT_FAIL", "EXIT_BAD_INPUT", "add_config_args",
           "load_model", "progress_log", "write_json", "registered_commands", "build_parser", "run", "main"]

EXIT_OK, EXIT_FAIL, EXIT_BAD_INPUT = 0, 1, 2
#: the entry-point group through which other packages add commands
ENTRY_POINT_GROUP = "mpcgen.commands"

Log = Callable[[str], None]


@dataclass(frozen=True)
class Command:
    """One ``mpcgen`` command."""

    #: the word after ``mpcgen``
    name: str
    #: one line for ``mpcgen --help``
    help: str
    #: adds the command's options to its parser
    arguments: Callable[[argparse.ArgumentParser], None]
    #: runs the command on the parsed arguments; returns the exit code
    run: Callable[[argparse.Namespace], int]


def topology_of(model: Model) -> Topology[Any]:
    """The model's topology plugin (imported when a command needs it: ``mpcgen --version`` and ``--help``
    stay fast)."""
    from codegen.topology import topology_of as of

    return of(model)


def with_trained_tables(model: Model, strategies: Sequence[str], log: Log) -> Model:
    """``codegen.stages.training.with_trained_tables``, imported when a command needs it."""
    from codegen.stages.training import with_trained_tables as trained

    return trained(model, strategies, log)


def write_csv_rows(path: Path, rows: list[dict[str, object]]) -> None:
    """``codegen.results.write_csv_rows``, imported when a command needs it."""
    from codegen.results import write_csv_rows as write

    write(path, rows)


def _err(msg: str) -> None:
    print(f"mpcgen: error: {msg}", file=sys.stderr)


def progress_log(quiet: bool) -> Log:
    """A progress logger: one line per message on stderr, nothing when ``quiet``."""

    def log(msg: str) -> None:
        if not quiet:
            print(msg, file=sys.stderr, flush=True)

    return log


def add_config_args(p: argparse.ArgumentParser, target: bool = False) -> None:
    """The config file and its overrides (``--strategy``, ``--set SECTION.FIELD=VALUE``, ...), and ``-q``."""
    from codegen.config import owners, schema_for, strategies_of
    from codegen.numfmt import CONFIG_FORMATS
    from codegen.registry import topology_names

    def choices(path: str) -> str:  # "a, b (topology); c (other topology)" from each topology's schema
        return "; ".join(f"{', '.join(map(str, schema_for(t)[path].choices))} ({t})" for t in owners(path))

    p.add_argument("config", help="configuration file (TOML)")
    p.add_argument("--strategy", help="override controller.strategy: " + "; ".join(
        f"{', '.join(strategies_of(t))} ({t})" for t in topology_names()))
    p.add_argument("--predictor", help=f"override controller.predictor: {choices('controller.predictor')}")
    p.add_argument("--tables", help=f"override controller.tables: {choices('controller.tables')}")
    p.add_argument("--number-format", dest="number_format",
                   help=f"override controller.number_format ({', '.join(CONFIG_FORMATS)})")
    dc = p.add_mutually_exclusive_group()
    dc.add_argument("--delay-compensation", dest="delay", action="store_const", const=True,
                    help="controller.delay_compensation = true: predict k+1 under the applied decision, choose "
                         "for k+2 (every topology)")
    dc.add_argument("--no-delay-compensation", dest="delay", action="store_const", const=False,
                    help="controller.delay_compensation = false: choose for k+1 (where the topology allows it: "
                         f"{', '.join(t for t in topology_names() if schema_for(t)['controller.delay_compensation'].choices != (True,))})")
    if target:
        p.add_argument("--target", help="override target.name (host, stm32h743, tms320f28377), "
                                        "or 'all': one folder per target under -o")
    p.add_argument("--set", dest="sets", action="append", default=[], metavar="SECTION.FIELD=VALUE",
                   help="override any config field (repeatable), e.g. --set controller.eps_t_nm=0.5")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress output")


def load_model(args: argparse.Namespace) -> Model:
    """The config of :func:`add_config_args`' arguments, loaded and checked (warnings to stderr)."""
    from codegen.config import load_config, parse_override

    overrides: dict[str, object] = {}
    for text in args.sets:
        k, v = parse_override(text)
        overrides[k] = v
    for attr, key in (("strategy", "controller.strategy"), ("predictor", "controller.predictor"),
                      ("tables", "controller.tables"), ("number_format", "controller.number_format"),
                      ("delay", "controller.delay_compensation"),
                      ("target", "target.name")):
        v = getattr(args, attr, None)
        if v is not None:
            overrides[key] = v
    model = load_config(args.config, overrides)
    for w in model.warnings:
        print(f"mpcgen: warning: {w}", file=sys.stderr)
    return model


def _strategies(args: argparse.Namespace, model: Model) -> list[str]:
    """``--strategies`` (a comma list), else ``--strategy`` alone, else every strategy of the config
    strategy's family (``codegen.config.family_strategies``: a strategy of another family reads other
    config fields)."""
    listed = getattr(args, "strategies", None)
    if listed is not None and getattr(args, "strategy", None) is not None:
        raise UsageError("--strategy and --strategies: give one of them")
    if listed is None and getattr(args, "strategy", None) is not None:
        return [model.controller.strategy]
    return cliargs.strategy_list("--strategies", listed, model, _family(model))


def _family(model: Model) -> tuple[str, ...]:
    """The strategies of the family of ``model``'s strategy, in report order."""
    from codegen.config import family_strategies

    return family_strategies(model.inverter.topology, model.controller.strategy)


def write_json(path: str | Path | None, data: dict[str, Any]) -> None:
    """Write ``data`` as indented JSON with sorted keys (folders created); nothing when ``path`` is None."""
    if path:
        write_atomic(Path(path), (json.dumps(data, indent=2, sort_keys=True) + "\n").encode())


# ---------------------------------------------------------------- generate
def cmd_generate(args: argparse.Namespace) -> int:
    from codegen.stages.generate import generate, quantisation_analysis

    every = args.target == "all"
    if every:
        args.target = None
    model = load_model(args)
    out = cliargs.output_dir("-o", args.output)
    log = progress_log(args.quiet)
    if every:  # one folder per target, same tables; the target-independent analysis computed once
        analysis = quantisation_analysis(model, log)
        paths = [p for t in TARGETS for p in generate(model.replace(target=t), out / t, log=log, analysis=analysis)]
    else:
        paths = generate(model, out, log=log)
    for p in paths:
        print(p)
    return EXIT_OK


# ---------------------------------------------------------------- verify
def cmd_verify(args: argparse.Namespace) -> int:
    from codegen.manifest import C_HASH_DEFINITION
    from codegen.numfmt import number_format
    from codegen.stages.verify import check_verify_memory, verify_strategy

    model = load_model(args)
    cliargs.at_least("--states", args.states, 1)
    cliargs.output_file("--json", args.json)
    strategies = _strategies(args, model)
    check_verify_memory(model, strategies, args.states, closed_loop=not args.no_closed_loop)
    log = progress_log(args.quiet)
    model = with_trained_tables(model, strategies, log)
    results = []
    for s in strategies:
        variant = model.with_controller(strategy=s)
        log(f"verify {model.name} / {s}: building and comparing {args.states} states")
        try:
            r = verify_strategy(variant, args.states, log=log, closed_loop=not args.no_closed_loop)
        except MemoryError:  # the estimate checked above is an estimate: other processes take memory too
            raise UsageError(f"--states = {args.states}: verifying {s} ran out of memory: lower --states") from None
        results.append(r)
        print(f"{s:12s} states {r.states:>9d}  mismatches {r.mismatches}  ({r.states_per_s:,.0f} states/s, "
              f"closed-loop {r.sources.get('closed_loop', 0)}, adversarial {r.sources['adversarial']}, "
              f"random {r.sources['random']}, guard trips {r.faulted_states})")
        compiled = "" if r.compiled_c_hash == r.c_hash else \
            f"; compiled and compared: the {r.compiled_target} C, C hash {r.compiled_c_hash}"
        print(f"{'':12s} C hash {r.c_hash} (the C generated for {r.c_hash_target}{compiled})")
        if number_format(variant.controller.number_format).quantised:  # numerics.md "Saturation inside the guard"
            passing = r.states - r.faulted_states
            sat = "; ".join(f"{site}: {k} of {passing}" for site, k in r.saturations.items()) or "none"
            print(f"{'':12s} saturations inside the guard (states passing it): {sat}")
        if r.mismatches:
            print(r.first_mismatch)
    write_json(args.json, {
        "config": model.name, "config_hash": model.config_hash(), "version": __version__,
        "target": model.target, "c_hash_definition": C_HASH_DEFINITION,
        "strategies": {r.strategy: r.as_dict() for r in results},
    })
    return EXIT_OK if all(r.mismatches == 0 for r in results) else EXIT_FAIL


# ---------------------------------------------------------------- simulate
def cmd_simulate(args: argparse.Namespace) -> int:
    model = load_model(args)
    cliargs.output_file("--json", args.json)
    plots = cliargs.output_dir("--plots", args.plots) if args.plots else None
    traces = cliargs.output_file("--traces", args.traces)
    log = progress_log(args.quiet)
    topo = topology_of(model)
    if args.sweep_eps is not None:
        if traces is not None:
            raise UsageError("--traces goes with a scenario run, not with --sweep-eps")
        eps = cliargs.check_sweep_eps("--sweep-eps", cliargs.sweep_values("--sweep-eps", args.sweep_eps), model)
        data = topo.sweep_eps(model, eps, log=log)
    else:
        strategies = _strategies(args, model)
        model = with_trained_tables(model, strategies, log)
        data = topo.simulate(model, strategies, plots, log=log, traces=traces)
    print(data.pop("_table"))
    # the plant simulated (not in the config hash: it never reaches the C); actuation_delay_periods
    # None: the delay the step compensates (docs/config.md [plant])
    data["plant"] = dataclasses.asdict(model.plant)
    if args.paper:
        side = topo.paper_table(model, data)
        print()
        print(side.pop("_table"))
        data["paper"] = side
    for warning in data.pop("_warnings", []):
        print(f"mpcgen: warning: {warning}", file=sys.stderr)
    write_json(args.json, data)
    return EXIT_FAIL if args.strict and data.get("tracking_failed") else EXIT_OK


# ---------------------------------------------------------------- tables
def cmd_tables(args: argparse.Namespace) -> int:
    model = load_model(args)
    if args.derive:
        if not args.output:
            raise UsageError("--derive needs -o FILE: the file the trained switch tables are written to")
        out = cliargs.output_file("-o", args.output)
        assert out is not None
        print(topology_of(model).export_tables(model, out, log=progress_log(args.quiet)))
        return EXIT_OK
    if args.output:
        raise UsageError("-o FILE goes with --derive (write the trained switch tables)")
    json_path = cliargs.output_file("--json", args.json)
    csv_path = cliargs.output_file("--csv", args.csv)
    topo = topology_of(model)
    print(topo.tables_text(model, args.utilisation, log=progress_log(args.quiet)))
    if json_path or csv_path:
        rows = topo.tables_rows(model, args.utilisation, log=progress_log(args.quiet))
        if json_path:
            write_json(str(json_path), {"config": model.name, "config_hash": model.config_hash(),
                                         "topology": topo.name, "rows": rows})
        if csv_path:
            write_csv_rows(csv_path, rows)
    return EXIT_OK


# ---------------------------------------------------------------- bench
def cmd_bench(args: argparse.Namespace) -> int:
    from codegen.stages.bench import BENCH_BOARDS, bench

    model = load_model(args)
    cliargs.at_least("--repeats", args.repeats, 1)
    cliargs.output_file("--json", args.json)
    strategies, log = _strategies(args, model), progress_log(args.quiet)
    model = with_trained_tables(model, strategies, log)
    if args.board is not None and not args.emulated:
        raise UsageError(f"--board = {args.board}: the board of --emulated; add --emulated")
    data = bench(model, strategies, emulated=args.emulated, repeats=args.repeats, log=log,
                 board=args.board or BENCH_BOARDS[0])
    print(data.pop("_table"))
    write_json(args.json, data)
    return EXIT_OK


# ---------------------------------------------------------------- firmware
def cmd_firmware(args: argparse.Namespace) -> int:
    from codegen.stages.firmware import BOARDS, write_firmware_project

    model = load_model(args)
    if args.board not in BOARDS:
        raise UsageError(f"--board = {args.board!r}: unknown board; allowed: {', '.join(BOARDS)}")
    out = cliargs.output_dir("-o", args.output)
    # generated code never trains: trained tables come from the config's tables file
    paths = write_firmware_project(model, topology_of(model).derive(model), args.board, out)
    print(f"wrote {len(paths)} files to {args.output}; build with: make -C {args.output}")
    return EXIT_OK


# ---------------------------------------------------------------- report
def cmd_report(args: argparse.Namespace) -> int:
    import tempfile

    from codegen.manifest import C_HASH_DEFINITION
    from codegen.stages.quantisation import analyse, fixed_twin
    from codegen.stages.quantreport import c_hashes, markdown, plots, report_name

    model = load_model(args)
    cliargs.at_least("--states", args.states, 1)
    cliargs.output_file("--json", args.json)
    out = cliargs.output_dir("-o", args.output) if args.output else None
    log = progress_log(args.quiet)
    twin = fixed_twin(model)
    if twin is not model:
        log(f"report: {model.name} is {model.controller.number_format}; analysing its fixed-point twin "
            f"(controller.number_format = {twin.controller.number_format})")
        model = twin
    strategies = _strategies(args, model)
    model = with_trained_tables(model, strategies, log)
    with tempfile.TemporaryDirectory(prefix="mpcgen-report-") as tmp:
        traces = Path(tmp) if out is not None else None
        data = analyse(model, strategies, random_states=args.states, log=log, traces=traces)
        files = plots(model, data, traces, out) if out is not None else None
    hashes = c_hashes(model, strategies)
    text = markdown(model, data, hashes, files)
    if out is not None:
        (out / report_name(model)).write_text(text)
        print(out / report_name(model))
        for names in (files or {}).values():
            for name in names:
                print(out / name)
    else:
        print(text, end="")
    write_json(args.json, {**data, "target": model.target, "c_hash_definition": C_HASH_DEFINITION,
                           "strategies": {s: {**d, "c_hash_target": model.target, "c_hash": hashes[s]}
                                          for s, d in data["strategies"].items()}})
    return EXIT_OK


# ---------------------------------------------------------------- sweep
def cmd_sweep(args: argparse.Namespace) -> int:
    from codegen.stages import sweep

    outputs = {k: cliargs.output_file(f"--{k}", getattr(args, k)) for k in ("json", "csv", "plot")}
    plot = outputs["plot"]
    if plot is not None and plot.suffix.lower() != ".png":
        raise UsageError(f"--plot = {plot}: the plot is written as PNG; give a file name ending in .png")
    cliargs.at_least("--monte-carlo", args.monte_carlo, 0)
    cliargs.at_least("--seed", args.seed, 0)
    model = load_model(args)
    return sweep.command(args, model, progress_log(args.quiet), _strategies(args, model), outputs)


# ---------------------------------------------------------------- tune
def cmd_tune(args: argparse.Namespace) -> int:
    from codegen.stages import tune

    out = cliargs.output_dir("-o", args.output) if args.output else None
    model = load_model(args)
    return tune.command(args, model, progress_log(args.quiet), _strategies(args, model), out)


# ---------------------------------------------------------------- study
def cmd_study(args: argparse.Namespace) -> int:
    from codegen.stages import study

    out = cliargs.output_dir("-o", args.output) if args.output else None
    return study.command(args, load_model(args), progress_log(args.quiet), out)


# ---------------------------------------------------------------- the commands and their options
def _generate_args(g: argparse.ArgumentParser) -> None:
    add_config_args(g, target=True)
    g.add_argument("-o", "--output", required=True, help="output directory")


def _verify_args(v: argparse.ArgumentParser) -> None:
    add_config_args(v)
    v.add_argument("--states", type=cliargs.count, default=1_000_000, help="states per strategy (default 1e6)")
    v.add_argument("--strategies", help="comma list (default: every strategy of the topology)")
    v.add_argument("--no-closed-loop", action="store_true", help="skip the recorded closed-loop states")
    v.add_argument("--json", help="write results as JSON")


def _simulate_args(s: argparse.ArgumentParser) -> None:
    add_config_args(s)
    s.add_argument("--strategies", help="comma list (default: all of the topology)")
    s.add_argument("--json", help="write metrics as JSON")
    s.add_argument("--plots", help="directory for PNG plots")
    s.add_argument("--traces", metavar="FILE",
                   help="write every run's time series (npz; CSV if FILE ends in .csv), one column per signal")
    s.add_argument("--paper", action="store_true",
                   help="print the paper's published figures next to ours, with the ratios the paper draws")
    s.add_argument("--sweep-eps", metavar="START:STOP:STEP",
                   help="threshold sweep of the MPTC paper's Tables 1-2 with strategy s1 (e.g. 0.1:1.5:0.1)")
    s.add_argument("--strict", action="store_true",
                   help="exit 1 when a run's tracking verdict is 'failed' (speed off its reference at the end of "
                        "a segment, torque held at the speed loop's limit, or a guard trip); the results are "
                        "written either way")


def _tables_args(t: argparse.ArgumentParser) -> None:
    add_config_args(t)
    t.add_argument("--utilisation", choices=("published", "training"), default=None,
                   help="topologies with trained switch tables: derive them from the published utilisation "
                        "tables or from a training run (default)")
    t.add_argument("--derive", action="store_true",
                   help="run the training and write the s2/s3 tables with their provenance to -o FILE "
                        "(name that file in the config as controller.tables_file)")
    t.add_argument("-o", "--output", help="with --derive: the tables file to write (JSON)")
    t.add_argument("--json", help="also write the tables as JSON rows (each row names its table)")
    t.add_argument("--csv", help="also write the tables as CSV (one row per table cell)")


def _bench_args(b: argparse.ArgumentParser) -> None:
    add_config_args(b)
    b.add_argument("--strategies", help="comma list (default: all of the topology)")
    b.add_argument("--emulated", action="store_true", help="instructions per step on the emulated Cortex-M7 (QEMU)")
    b.add_argument("--board", choices=("qemu-m7", "qemu-m3"),
                   help="the emulated board of --emulated: qemu-m7 (default; Cortex-M7 with FPU, cycle estimate) "
                        "or qemu-m3 (Cortex-M3 without FPU: fixed point against float32 in soft float, every "
                        "strategy, and the M7's fixed/float32 ratio)")
    b.add_argument("--repeats", type=int, default=5, help="timing repeats, best kept (default 5)")
    b.add_argument("--json", help="write results as JSON")


def _firmware_args(f: argparse.ArgumentParser) -> None:
    add_config_args(f)
    f.add_argument("--board", required=True, help="stm32h743, tms320f28377, qemu-m7 or host")
    f.add_argument("-o", "--output", required=True, help="output directory")


def _sweep_args(w: argparse.ArgumentParser) -> None:
    add_config_args(w)
    w.add_argument("--strategies", help="comma list (default: all of the topology)")
    w.add_argument("--param", action="append", default=[], metavar="SECTION.FIELD=LIST_OR_RANGE",
                   help="a grid axis (repeatable): a comma list (0.2,0.5,1) or START:STOP:STEP")
    w.add_argument("--monte-carlo", dest="monte_carlo", type=int, default=0, metavar="N",
                   help="N runs with parameters drawn around the config's (--spread)")
    w.add_argument("--spread", action="append", default=[], metavar="SECTION.FIELD=+-PCT",
                   help="Monte Carlo: uniform spread of a field in percent (repeatable), e.g. plant.rs_ohm=+-20")
    w.add_argument("--seed", type=int, default=1, help="Monte Carlo seed (default 1)")
    _runner_args(w)
    w.add_argument("--json", help="write every run's parameters and metrics as JSON")
    w.add_argument("--csv", help="write one row per run and strategy as CSV")
    w.add_argument("--plot", help="PNG: metric against the parameter, or the Monte Carlo distribution")


def _runner_args(w: argparse.ArgumentParser) -> None:
    """Where the runs of ``sweep`` and ``tune`` go: a LocalCluster, a scheduler (TLS) or this process."""
    w.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                   help="a running dask.distributed scheduler, tcp:// or tls:// (default: a LocalCluster on this "
                        "machine's cores)")
    w.add_argument("--workers", type=int, default=None, help="LocalCluster workers (default: one per core)")
    w.add_argument("--serial", action="store_true", help="run in this process, no Dask (reference for checks)")
    w.add_argument("--tls-ca-file", dest="tls_ca_file", metavar="PEM",
                   help="TLS: the CA that signed the scheduler's and workers' certificates (with --tls-cert, "
                        "--tls-key; for --scheduler tls://..., or a LocalCluster over TLS)")
    w.add_argument("--tls-cert", dest="tls_cert", metavar="PEM", help="TLS: this client's certificate")
    w.add_argument("--tls-key", dest="tls_key", metavar="PEM", help="TLS: this client's private key")


def _tune_args(t: argparse.ArgumentParser) -> None:
    add_config_args(t)
    t.add_argument("--strategies", help="comma list (default: all of the topology)")
    t.add_argument("--weight", action="append", default=[], metavar="SECTION.FIELD[=LO:HI]",
                   help="a cost weight to tune on a log scale (repeatable), e.g. controller.lambda_psi_nm_per_wb; "
                        "default range: the config's value / 10^1.5 .. x 10^1.5")
    t.add_argument("--threshold", action="append", default=[], metavar="SECTION.FIELD[=LO:HI]",
                   help="a threshold to tune on a linear scale (repeatable), e.g. controller.eps_t_nm; default "
                        "range: 0 .. 2 x the config's value")
    t.add_argument("--objectives", metavar="LIST",
                   help="figures the front trades, minimised (default T_rip_RMSE_nm,psi_rip_RMSE_wb,"
                        "THD_ia_all_bins_percent, and f_ave_hz when controller.lambda_u is tuned; short names "
                        "T_rip, psi_rip, THD, THD_all, f_ave, Vo, i_peak, Cal)")
    t.add_argument("--grid", type=int, default=None,
                   help="values per field in round 0 (default 9, 5, 4, 3 for 1, 2, 3, more fields)")
    t.add_argument("--rounds", type=int, default=2, help="refinement rounds near the front (default 2)")
    t.add_argument("--focus", type=int, default=3,
                   help="each round refines around the N admissible-front points nearest the ideal point (default "
                        "3; 0: the whole admissible front)")
    _runner_args(t)
    t.add_argument("-o", "--output", metavar="DIR",
                   help="write tune.md, tune.json, tune.csv and front_<a>_<b>.png there (default: the table on "
                        "stdout)")


def _study_args(t: argparse.ArgumentParser) -> None:
    add_config_args(t)
    t.add_argument("--horizons", default="1-5", metavar="A-B|LIST",
                   help="the horizons N compared: A-B or a comma list (default 1-5)")
    t.add_argument("--fsw-khz", dest="fsw_khz", type=float, default=None, metavar="KHZ",
                   help="the switching frequency every N is matched to (default: f_ave of N = 1 at the config's "
                        "controller.lambda_u)")
    t.add_argument("--tolerance", type=float, default=3.0, metavar="PCT",
                   help="matched when f_ave is within this many percent of the target (default 3)")
    t.add_argument("--max-runs", dest="max_runs", type=int, default=16,
                   help="closed-loop runs per N at most while searching lambda_u (default 16)")
    t.add_argument("--bench", action="append", default=[], metavar="FILE",
                   help="mpcgen bench --emulated --json output (repeatable): fills the M7 cycles of the N whose "
                        "config hash it names")
    _runner_args(t)
    t.add_argument("-o", "--output", metavar="DIR",
                   help="write study.md, study.json and study.png there (default: the table on stdout)")


def _report_args(r: argparse.ArgumentParser) -> None:
    add_config_args(r)
    r.add_argument("--strategies", help="comma list (default: all of the topology)")
    r.add_argument("--states", type=cliargs.count, default=20_000, help="random states per strategy (default 20000)")
    r.add_argument("-o", "--output", help="directory for <prefix>_quantisation.md and the PNG plots "
                                          "(default: the markdown on stdout)")
    r.add_argument("--json", help="write the analysis as JSON")


#: codegen's own commands, in ``mpcgen --help`` order
COMMANDS: tuple[Command, ...] = (
    Command("generate", "write the C controller for a target", _generate_args, cmd_generate),
    Command("verify", "compiled C vs Python reference, bit for bit", _verify_args, cmd_verify),
    Command("simulate", "closed-loop scenario runs with the paper's metrics", _simulate_args, cmd_simulate),
    Command("tables", "print derived switch tables and vector sets", _tables_args, cmd_tables),
    Command("bench", "execution cost per step, all strategies side by side", _bench_args, cmd_bench),
    Command("firmware", "write a buildable firmware project for a board", _firmware_args, cmd_firmware),
    Command("sweep", "parameter grids and Monte Carlo mismatch studies of simulate, on Dask", _sweep_args, cmd_sweep),
    Command("tune", "cost weights and thresholds from the closed loop: the front, a recommended value, on Dask",
            _tune_args, cmd_tune),
    Command("study", "long-horizon study: THD, torque ripple and decoder nodes per horizon at a matched "
                     "switching frequency", _study_args, cmd_study),
    Command("report", "quantisation report of the fixed-point controller (formats, errors, agreement with "
                      "float32, closed loop)", _report_args, cmd_report),
    # defined at the end of this module: looked up when called
    Command("evidence", "one self-contained HTML page of a run's verify, simulate, report, bench and hil outputs",
            lambda p: _evidence_args(p), lambda a: cmd_evidence(a)),
)


def _warn(msg: str) -> None:
    print(f"mpcgen: warning: {msg}", file=sys.stderr)


def registered_commands() -> list[Command]:
    """The commands other packages register in :data:`ENTRY_POINT_GROUP`, by name.  An entry point
    that does not load, or names no :class:`Command` of its own name or one of codegen's, is left out
    with a warning: the other commands keep working."""
    own = {c.name for c in COMMANDS}
    found: dict[str, Command] = {}
    for ep in sorted(entry_points(group=ENTRY_POINT_GROUP), key=lambda e: e.name):
        if ep.name in found:
            continue
        try:
            command = ep.load()
        except Exception as exc:  # a broken plugin must not take the other commands down
            _warn(f"command {ep.name!r} ({ep.value}) not loaded: {exc}")
            continue
        if not isinstance(command, Command) or command.name != ep.name or ep.name in own:
            _warn(f"command {ep.name!r} ({ep.value}) left out: not a codegen.cli.Command named {ep.name!r}, "
                  "or the name of a codegen command")
            continue
        found[ep.name] = command
    return list(found.values())


def build_parser(commands: Sequence[Command] | None = None) -> argparse.ArgumentParser:
    """The ``mpcgen`` parser with ``commands`` (default: codegen's and the registered ones)."""
    p = argparse.ArgumentParser(prog="mpcgen", allow_abbrev=False,  # --plot must not silently mean --plots
                                description="FCS-MPC code generator for PMSM drives: generate, verify bit for bit, "
                                            "simulate, benchmark.")
    p.add_argument("--version", action="version", version=f"mpcgen {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    for command in (*COMMANDS, *registered_commands()) if commands is None else commands:
        c = sub.add_parser(command.name, help=command.help, allow_abbrev=False)
        command.arguments(c)
        c.set_defaults(func=command.run)
    return p


def run(parser: argparse.ArgumentParser, argv: Sequence[str] | None = None) -> int:
    """Parse ``argv`` and run the chosen command; errors become one line and an exit code."""
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: 2 on bad usage, 0 on --help
        return int(exc.code or 0)
    try:
        return int(args.func(args))
    except (ConfigError, UsageError) as exc:
        _err(str(exc))
        return EXIT_BAD_INPUT
    except MpcgenError as exc:
        _err(str(exc))
        return EXIT_FAIL
    except KeyboardInterrupt:
        _err("interrupted")
        return 130


def main(argv: Sequence[str] | None = None) -> int:
    """``mpcgen`` (the console script): codegen's commands and the registered ones.  ``mpcgen --version``
    answers before the commands (and their entry points) are collected."""
    if list(sys.argv[1:] if argv is None else argv) == ["--version"]:
        print(f"mpcgen {__version__}")
        return EXIT_OK
    return run(build_parser(), argv)


# ---------------------------------------------------------------- evidence
def _evidence_args(e: argparse.ArgumentParser) -> None:
    add_config_args(e)
    e.add_argument("--verify", action="append", default=[], metavar="FILE",
                   help="mpcgen verify --json output (repeatable: one per number format)")
    e.add_argument("--simulate", metavar="FILE", help="mpcgen simulate --json output")
    e.add_argument("--plots", metavar="DIR", help="mpcgen simulate --plots folder: every PNG shown inline")
    e.add_argument("--report", metavar="DIR_OR_MD", help="mpcgen report -o folder, or its <prefix>_quantisation.md")
    e.add_argument("--bench", metavar="FILE", help="mpcgen bench --json output")
    e.add_argument("--hil", action="append", default=[], metavar="FILE", help="mpcgen hil --json output (repeatable)")
    e.add_argument("--manifest", action="append", default=[], metavar="FILE",
                   help="the <prefix>_manifest.json mpcgen generate writes (repeatable)")
    e.add_argument("--allow-mixed", action="store_true",
                   help="include inputs naming another config hash (flagged red) instead of refusing them")
    e.add_argument("-o", "--output", required=True, metavar="FILE", help="the HTML page to write")


def _given_overrides(args: argparse.Namespace) -> tuple[str, ...]:
    """The overrides on the command line as ``section.field=value``, in load order."""
    flags = (("strategy", "controller.strategy"), ("predictor", "controller.predictor"),
             ("tables", "controller.tables"), ("number_format", "controller.number_format"),
             ("delay", "controller.delay_compensation"))
    given = [f"{key}={getattr(args, attr)}" for attr, key in flags if getattr(args, attr, None) is not None]
    return (*args.sets, *given)


def _evidence_identities(model: Model, named: set[str], log: Log) -> dict[str, Any]:
    """The config hashes that are ``model``'s: its own, its fixed-point twin's (what ``report`` analyses)
    and, only when an input names a hash not yet known, each of those with the tables trained on its
    scenario (what ``verify``, ``simulate``, ``bench`` ... run)."""
    from codegen.evidence import Identity
    from codegen.stages.quantisation import fixed_twin

    twin = fixed_twin(model)
    variants = [("config", model)]
    if twin is not model:
        variants.append((f"{twin.controller.number_format} twin, as report analyses it", twin))
    ids: dict[str, Any] = {}
    for label, m in variants:
        ids.setdefault(m.config_hash(), Identity(label, m.controller.number_format))
    for label, m in variants:
        if named <= ids.keys():
            break
        trained = with_trained_tables(m, _family(m), log)
        ids.setdefault(trained.config_hash(), Identity(f"{label}, with trained tables", m.controller.number_format))
    return ids


def cmd_evidence(args: argparse.Namespace) -> int:
    import hashlib

    from codegen import evidence

    model = load_model(args)
    out = cliargs.output_file("-o", args.output)
    assert out is not None
    log = progress_log(args.quiet)
    inputs = evidence.collect(verify=args.verify, simulate=args.simulate, plots=args.plots, report=args.report,
                              bench=args.bench, hil=args.hil, manifest=args.manifest)
    identities = _evidence_identities(model, evidence.named_config_hashes(inputs), log)
    if not args.allow_mixed:
        evidence.check_belongs(inputs.all(), identities, args.config)
    facts = evidence.ConfigFacts(
        path=args.config, sha256=hashlib.sha256(Path(args.config).read_bytes()).hexdigest(), name=model.name,
        config_hash=model.config_hash(), topology=topology_of(model).name, strategy=model.controller.strategy,
        number_format=model.controller.number_format, target=model.target, version=__version__,
        overrides=_given_overrides(args))
    out.write_text(evidence.page(facts, inputs, identities), encoding="utf-8")
    log(f"evidence: {len(inputs.all()) + len(inputs.plots)} inputs -> {out}")
    print(out)
    return EXIT_OK


if __name__ == "__main__":  # run as codegen.cli, so that registered commands see this module's Command
    from codegen import cli as _cli

    sys.exit(_cli.main())
