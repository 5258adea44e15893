"""The referee: replay an AL program on a simulated arm in a true world.

:func:`replay` runs a program once in the believed world and N times in worlds sampled from
the task's uncertainty, on the arm model with Coal contact; see :mod:`synth.replay.run`.
Modules: :mod:`.truth` (sampled worlds, hand errors), :mod:`.capture` (pin–hole geometry),
:mod:`.contact` (what the held pin touches), :mod:`.reach` (inverse kinematics and why it
fails), :mod:`.machine` (the AL machine), :mod:`.report` (results), :mod:`.run` (nominal run and
Monte Carlo), :mod:`.proof` (the planner's proof), :mod:`.trials` (the trial pool),
:mod:`.cluster` (Dask). The solids are the task's, shared with the planner:
:mod:`synth.models.workcell`. The command line is :mod:`synth.cli`.
"""

from __future__ import annotations

from synth.replay.machine import PinState, ReplayMachine, ReplayOptions, ViolationStop
from synth.replay.report import (
    OUTCOMES,
    MonteCarloReport,
    Outcome,
    ReplayReport,
    RunReport,
    Violation,
    ViolationKind,
    wilson_interval,
)
from synth.replay.run import (
    ReplayContext,
    machine_for,
    replay_context,
    replay_program,
    run_machine,
    run_nominal,
    run_trial,
    run_world,
    summarise,
    trial_seed,
)
from synth.replay.truth import HandErrors, TrueWorld, nominal_world, sample_world

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
    "machine_for",
    "nominal_world",
    "replay_context",
    "replay_program",
    "run_machine",
    "run_nominal",
    "run_trial",
    "run_world",
    "sample_world",
    "summarise",
    "trial_seed",
    "wilson_interval",
]
