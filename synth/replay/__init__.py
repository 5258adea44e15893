"""The referee: replay an AL program on a simulated arm in a true world (issue 6).

:func:`replay` runs a program once in the believed world and N times in worlds sampled from
the task's uncertainty, on the arm model with Coal contact; see :mod:`synth.replay.run`.
Modules: :mod:`.truth` (sampled worlds, hand errors), :mod:`.capture` (pin–hole geometry),
:mod:`.contact` (what the held pin touches), :mod:`.reach` (inverse kinematics and why it
fails), :mod:`.machine` (the AL machine), :mod:`.report` (results), :mod:`.run` (nominal run and
Monte Carlo), :mod:`.cli_command` (``synth replay``). The solids are the task's, shared with the
planner: :mod:`synth.models.workcell`.

Names are imported on first use (PEP 562), so ``import synth.replay.cli_command`` stays light.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from synth.replay.machine import PinState, ReplayMachine, ReplayOptions, ViolationStop
    from synth.replay.report import (
        OUTCOMES,
        MonteCarloReport,
        Outcome,
        ReplayReport,
        RunReport,
        Violation,
        ViolationKind,
        replay_summary,
        wilson_interval,
    )
    from synth.replay.run import (
        ReplayContext,
        build_context,
        machine_for,
        replay,
        replay_program,
        run_machine,
        run_nominal,
        run_trial,
        run_world,
        summarise,
        trial_seed,
    )
    from synth.replay.truth import HandErrors, TrueWorld, nominal_world, sample_world

_HOMES = {
    "synth.replay.machine": ("PinState", "ReplayMachine", "ReplayOptions", "ViolationStop"),
    "synth.replay.report": (
        "OUTCOMES",
        "MonteCarloReport",
        "Outcome",
        "ReplayReport",
        "RunReport",
        "Violation",
        "ViolationKind",
        "replay_summary",
        "wilson_interval",
    ),
    "synth.replay.run": (
        "ReplayContext",
        "build_context",
        "machine_for",
        "replay",
        "replay_program",
        "run_machine",
        "run_nominal",
        "run_trial",
        "run_world",
        "summarise",
        "trial_seed",
    ),
    "synth.replay.truth": ("HandErrors", "TrueWorld", "nominal_world", "sample_world"),
}
_WHERE = {name: module for module, names in _HOMES.items() for name in names}

__all__ = [
    "OUTCOMES",
    "HandErrors",
    "MonteCarloReport",
    "Outcome",
    "PinState",
    "ReplayContext",
    "ReplayMachine",
    "ReplayOptions",
    "ReplayReport",
    "RunReport",
    "TrueWorld",
    "Violation",
    "ViolationKind",
    "ViolationStop",
    "build_context",
    "machine_for",
    "nominal_world",
    "replay",
    "replay_program",
    "replay_summary",
    "run_machine",
    "run_nominal",
    "run_trial",
    "run_world",
    "sample_world",
    "summarise",
    "trial_seed",
    "wilson_interval",
]
assert sorted(__all__) == sorted(_WHERE)


def __getattr__(name: str) -> Any:
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module 'synth.replay' has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)
