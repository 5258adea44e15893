"""Jobs that draw a stored plan: its plan picture, its 3-D view and the trace of its replay.

They run in the worker processes like :mod:`server.service`'s jobs, take plain values and call
synth's picture functions (:mod:`synth.pictures`, :mod:`synth.replay.trace`); the routes are in
:mod:`server.routers.pictures`.
"""

from __future__ import annotations

from typing import Any

from server.service import SpecKind, _spec_for_server

__all__ = ["plan_svg_job", "trace_job", "view_html_job"]


def pictured_strategy(result: dict[str, Any]) -> str:
    """The name of the strategy a stored plan's picture draws (``pictured``), "" if none.

    A single insertion's chosen strategy; a sequence's first step's. The sequence's result has
    no ``strategy``: its name read "", never matched, and every picture re-ran the plan's whole
    Monte Carlo proof (10 s for a two-step plan of 20 trials, against 1.6 s for a single one).
    """
    if "strategy" in result:
        return str((result["strategy"] or {}).get("name", ""))
    steps = result.get("steps") or [{}]
    return str((steps[0].get("strategy") or {}).get("name", ""))


def plan_svg_job(
    spec_body: str,
    kind: SpecKind,
    options: dict[str, Any],
    strategy: str,
    model_dirs: tuple[str, ...],
) -> bytes:
    """The plan picture (SVG) of the stored plan whose chosen strategy is ``strategy``.

    The picture needs the planner's records, which the store keeps only as JSON: plan again
    (deterministic) with the nominal proof only, and with the plan's own proof when that chose
    another candidate (a candidate the stored proof rejected).
    """
    from synth.pictures.plan import draw_plan, plan_picture
    from synth.pictures.render import figure_bytes
    from synth.pipeline import SynthesisOptions, synthesize
    from synth.replay.proof import ProofOptions
    from synth.strategies.options import PlanOptions

    spec = _spec_for_server(spec_body, kind, model_dirs)
    planner = PlanOptions(try_harder=options["try_harder"], exhaustive=options["exhaustive"])
    result = synthesize(
        spec,
        SynthesisOptions(plan=planner, proof=ProofOptions.for_task(spec, trials=0, workers=1)),
    )
    if result.pictured[0].name != strategy:
        trials = options["trials"] if options["validate"] else 0
        proof = ProofOptions.for_task(spec, trials=trials, seed=options["seed"], workers=1)
        result = synthesize(spec, SynthesisOptions(plan=planner, proof=proof))
    return figure_bytes(draw_plan(plan_picture(*result.pictured)), "svg")


def _trace(
    program: str, spec_body: str, kind: SpecKind, model_dirs: tuple[str, ...], **kw: Any
) -> tuple[Any, Any]:
    from synth.replay.run import replay_context
    from synth.replay.trace import record_run

    context = replay_context(program, _spec_for_server(spec_body, kind, model_dirs))
    return context, record_run(context, program="program.al", **kw)


def view_html_job(program: str, spec_body: str, kind: SpecKind, model_dirs: tuple[str, ...]) -> str:
    """The 3-D view (one HTML page) of ``program``'s nominal run on the stored task."""
    from synth.pictures.view import view_html, view_scene

    context, trace = _trace(program, spec_body, kind, model_dirs)
    return view_html(view_scene(context, trace, program))


def trace_job(
    program: str,
    spec_body: str,
    kind: SpecKind,
    trial: int | None,
    seed: int,
    model_dirs: tuple[str, ...],
) -> dict[str, Any]:
    """The trace (docs/trace.md) of the nominal run, or of Monte Carlo trial ``trial``."""
    _, trace = _trace(program, spec_body, kind, model_dirs, trial=trial, seed=seed)
    return trace.to_json()
