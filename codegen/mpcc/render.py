"""Template context of the long-horizon step (templates/mpcc/): values to print, already derived."""
from __future__ import annotations

from typing import Any

from codegen.model import Model
from codegen.mpcc.tables import MpccTables
from codegen.render import render_files, render_step_cdef, sincos_bound, step_context

__all__ = ["context", "render_mpcc", "render_cdef", "stack_bytes"]


def stack_bytes(t: MpccTables) -> int:
    """Bytes of the search's local arrays (the explicit stack, 4-byte reals and unsigned ints):
    children (distance, digit) per level, children count, next child and path digit per level,
    partial distance and index per level + 1."""
    n, b = t.n_vars, t.n_levels
    return 4 * (2 * n * b + 3 * n + 2 * (n + 1))


def context(model: Model, t: MpccTables, target: str, title: str, safe_text: str, doc: str,
            extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """The template context (``title``: the topology's name for the banner, ``safe_text``: its safe
    decision in words, ``doc``: the header's decision paragraph, ``extra``: what the topology's
    decision template prints)."""
    a = t.adapter
    return step_context(model, target, (a.input_record, a.output_record(t.horizon)), a.fault_bits, **{
        "consts": t.consts, "scaling": t.scaling, "sincos_tab": t.sincos_tab, "strategy": t.strategy,
        "fault_action": t.fault_action, "guard": a.guard, "topology_macro": a.topology_macro,
        "topo_template": a.template, "topology_title": title, "safe_text": safe_text, "topo_doc": doc,
        "horizon": t.horizon, "n_vars": t.n_vars, "n_levels": t.n_levels, "node_budget": t.node_budget,
        "node_budget_given": model.controller.node_budget is not None, "max_step": t.max_step,
        "delay": t.delay, "n_angles": t.horizon + t.delay + 1, "h": t.h, "w1": t.w1, "w2": t.w2,
        "lvl": t.lvl, "pw": t.pw, "udc_fields": a.udc_fields, "prev_field": a.prev_field,
        "neutral_point": t.neutral_point, "np_fields": a.neutral_point,
        "mid_digit": t.mid_digit if t.neutral_point else None, "stack_bytes": stack_bytes(t), "seq0": "out->seq" if t.horizon == 1 else "out->seq[0]", "delay_compensation": t.delay_compensation,
        "sincos_bound": sincos_bound(t.nf, "ANGLE_GUARD_RAD"), **(extra or {})})


def render_mpcc(model: Model, t: MpccTables, target: str, title: str, safe_text: str, doc: str,
                extra: dict[str, Any] | None = None) -> dict[str, str]:
    """File name -> text of the generated long-horizon step for ``target`` (:func:`context`)."""
    p = model.prefix
    return render_files({f"{p}_mpc.h": "mpcc/mpc.h.j2", f"{p}_mpc.c": "mpcc/mpc.c.j2",
                         "mpc_binding.h": "common/binding.h.j2"},
                        context(model, t, target, title, safe_text, doc, extra))


def render_cdef(model: Model, t: MpccTables) -> str:
    """cffi declarations of the host build."""
    return render_step_cdef(context(model, t, "host", "", "", ""))
