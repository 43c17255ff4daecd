"""Command-line values checked as the config is: one line naming the option, value and what is allowed.

Every check runs before any long job (a training run, a 10^6-state
verification), so a bad output path or count never surfaces after minutes
of work or as a traceback.  Failures raise :class:`codegen.errors.UsageError`
(exit code 2).
"""
from __future__ import annotations

import argparse
import math
import os
from pathlib import Path

from codegen.errors import UsageError
from codegen.model import Model
from codegen.outputs import output_error

__all__ = ["at_least", "output_dir", "output_file", "strategy_list", "sweep_values", "check_sweep_eps"]

#: most values a --sweep-eps range may expand to
MAX_SWEEP_VALUES = 200


def at_least(option: str, value: int, lowest: int) -> int:
    """``value`` if it is an integer >= ``lowest``."""
    if value < lowest:
        raise UsageError(f"{option} = {value}: must be an integer >= {lowest}")
    return value


def _writable_dir(option: str, d: Path, what: str) -> None:
    try:
        d.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise UsageError(f"{option} = {d}: {what} exists and is not a folder") from None
    except OSError as exc:
        raise UsageError(f"{option}: {output_error(exc, d)}") from None
    if not os.access(d, os.W_OK | os.X_OK):
        raise UsageError(f"{option} = {d}: the {what} is not writable")


def count(text: str) -> int:
    """A whole number of things as the docs write it: ``1000000``, ``1_000_000`` or ``1e6``."""
    try:
        return int(text)
    except ValueError:
        pass
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number (e.g. 1000000 or 1e6)") from None
    if not (x.is_integer() and abs(x) < 2**63):
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number (e.g. 1000000 or 1e6)")
    return int(x)


def output_dir(option: str, path: str | Path) -> Path:
    """A folder the command may write into (created if missing)."""
    d = Path(path)
    try:
        exists = d.exists()
    except OSError as exc:  # a name too long: exists() raises rather than answers
        raise UsageError(f"{option}: {output_error(exc, d)}") from None
    if exists and not d.is_dir():
        raise UsageError(f"{option} = {d}: exists and is not a folder; give a folder to write into")
    _writable_dir(option, d, "output folder")
    return d


def output_file(option: str, path: str | Path | None) -> Path | None:
    """A file the command may write (its folder created if missing); None passes through."""
    if path is None:
        return None
    f = Path(path)
    try:
        f.exists()
    except OSError as exc:  # a name too long: exists() raises rather than answers
        raise UsageError(f"{option}: {output_error(exc, f)}") from None
    if f.is_dir():
        raise UsageError(f"{option} = {f}: is a folder; give a file name")
    _writable_dir(option, f.parent, "folder of the output file")
    existed = f.exists()
    try:  # the only reliable test (root passes os.access on /proc): open it for appending
        with open(f, "a"):
            pass
    except OSError as exc:
        raise UsageError(f"{option} = {f}: cannot write the file ({exc.strerror or exc})") from None
    if not existed:
        f.unlink()
    return f


def strategy_list(option: str, text: str | None, model: Model, family: tuple[str, ...]) -> list[str]:
    """The strategies named by a comma list (all of ``family`` when the option is absent): the config
    strategy's family (``codegen.config.family_strategies``)."""
    if text is None:
        return list(family)
    chosen = [s.strip() for s in text.split(",") if s.strip()]
    if not chosen:
        raise UsageError(f"{option} = {text!r}: names no strategy; allowed: {', '.join(family)}")
    for s in chosen:
        if s not in family:
            raise UsageError(f"{option}: '{s}' is not a strategy of a {model.inverter.topology} inverter in the "
                             f"family of controller.strategy = '{model.controller.strategy}'; allowed: "
                             f"{', '.join(family)} (another family: set controller.strategy and its fields)")
    return chosen


def sweep_values(option: str, text: str) -> list[float]:
    """START:STOP:STEP (STEP > 0, STOP >= START) or a comma list of numbers."""
    form = "expected START:STOP:STEP with STEP > 0 (e.g. 0.1:1.5:0.1) or a comma list of numbers"
    try:
        if ":" in text:
            a, b, c = (float(v) for v in text.split(":"))
            if not all(math.isfinite(v) for v in (a, b, c)) or c <= 0 or b < a:
                raise ValueError
            n = int(math.floor((b - a) / c + 1e-9)) + 1
            if n > MAX_SWEEP_VALUES:
                raise UsageError(f"{option} = {text!r}: {n} values, at most {MAX_SWEEP_VALUES}")
            vals = [round(a + i * c, 10) for i in range(n)]
        else:
            vals = [float(v) for v in text.split(",")]
            if not all(math.isfinite(v) for v in vals):
                raise ValueError
    except ValueError:
        raise UsageError(f"{option} = {text!r}: {form}") from None
    if not vals:
        raise UsageError(f"{option} = {text!r}: {form}")
    return vals


def check_sweep_eps(option: str, values: list[float], model: Model) -> list[float]:
    """Torque thresholds within [0, rated torque), as ``controller.eps_t_nm`` is checked."""
    rated = model.motor.rated_torque_nm
    for v in values:
        if not 0.0 <= v < rated:
            raise UsageError(f"{option}: eps_T = {v:g} N*m outside [0, motor.rated_torque_nm = {rated:g}) "
                             f"(as controller.eps_t_nm)")
    return values
