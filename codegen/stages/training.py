"""The training stage: tables trained on the config's own scenario, for a config that asks for them
without naming the artefact.

A strategy whose tables are trained on the config's scenario takes them from
the artefact ``mpcgen tables CONFIG --derive -o FILE`` writes; the config
names it and loading the config reads it into the model (the topology's
config section).  ``mpcgen generate`` and ``mpcgen firmware`` never train:
without the artefact the topology's ``derive`` refuses in one line naming
that command.

The commands that run the controller on the host (verify, simulate, bench,
report, sweep, hil) run this stage first instead: the topology says whether
a strategy needs training (:meth:`codegen.topology.Training.needs_training`)
and trains (:meth:`~codegen.topology.Training.train`, its training run
cached in ``MPCGEN_CACHE``), reading the result into the model exactly as a
config's artefact is read.
"""
from __future__ import annotations

from collections.abc import Callable, Iterable

from codegen.errors import MpcgenError
from codegen.model import Model
from codegen.topology import topology_of

__all__ = ["lacks_trained_tables", "with_trained_tables"]

Log = Callable[[str], None]


def _silent(_msg: str) -> None:
    pass


def lacks_trained_tables(model: Model) -> bool:
    """True when ``model``'s strategy needs trained tables the model does not carry."""
    return topology_of(model).needs_training(model)


def with_trained_tables(model: Model, strategies: Iterable[str], log: Log = _silent) -> Model:
    """``model`` with the tables trained on its scenario read in, when one of ``strategies`` needs them;
    else ``model`` itself."""
    chosen = tuple(strategies)
    topo = topology_of(model)
    if not any(topo.needs_training(model.with_controller(strategy=s)) for s in chosen):
        return model
    trained = topo.train(model, log)
    if any(topo.needs_training(trained.with_controller(strategy=s)) for s in chosen):
        raise MpcgenError(f"training stage: the {topo.title} training did not give the tables "
                          f"{', '.join(chosen)} need")
    return trained
