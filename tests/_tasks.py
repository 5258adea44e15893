"""Task fixtures shared by the planner and replay tests: variants and the plannable set."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

from _paths import TASKS

from synth.models.loader import load_task
from synth.models.spec import TaskSpec
from synth.models.spec_fields import Pose
from synth.pipeline import Synthesis, SynthesisOptions, synthesize
from synth.replay.proof import ProofOptions


def with_base(spec: TaskSpec, x_cm: float, y_cm: float, yaw_deg: float) -> TaskSpec:
    """``spec`` with the arm standing at (x, y) on the table, turned by ``yaw`` about z."""
    manipulator = spec.manipulator
    assert manipulator is not None
    base = Pose.model_validate(
        {"translation": [f"{x_cm} cm", f"{y_cm} cm", "0 cm"], "rotation": [{"z": f"{yaw_deg} deg"}]}
    )
    arm = manipulator.arm.model_copy(update={"base": base})
    return spec.model_copy(update={"manipulator": manipulator.model_copy(update={"arm": arm})})


def plannable() -> list[Path]:
    """The fixture tasks ``synth plan`` accepts: with an insertion and a manipulator."""
    out = []
    for path in sorted(TASKS.glob("*.yaml")):
        spec = load_task(path)
        if spec.insertion is not None and spec.manipulator is not None:
            out.append(path)
    return out


def synthesized(task: Path | TaskSpec, trials: int = 0, seed: int = 0) -> Synthesis:
    """The pipeline's proven program for ``task`` with a proof of ``trials`` (one process).

    The proof of ``trials`` at the default 0.99 allows no failure below 100 trials, so a test
    that asserts ``attempts == 1`` says the planner's first choice was the proven one. A task
    file's synthesis is kept for the other tests of the process (a frozen record; several
    tests start from the seed's program).
    """
    if isinstance(task, Path):
        return _synthesized_file(task.resolve(), trials, seed)
    return _synthesize(task, trials, seed)


def _synthesize(task: Path | TaskSpec, trials: int, seed: int) -> Synthesis:
    options = SynthesisOptions(proof=ProofOptions(trials=trials, seed=seed, workers=1))
    base_dir = TASKS if isinstance(task, TaskSpec) else None
    return synthesize(task, options, base_dir=base_dir)


_synthesized_file = functools.cache(_synthesize)


def without_lifts(monkeypatch: Any) -> None:
    """Plan as before gross motions could be lifted over the workcell (synth/strategies/detour.py).

    For tests of what the planner does when a straight move is obstructed and nothing else
    helps: a refusal, or a sequence that goes back to another plan.
    """
    refuse = lambda *args, **kwargs: "lifts are off in this test"  # noqa: E731
    monkeypatch.setattr("synth.strategies.grasp.lift_over", refuse)
    monkeypatch.setattr("synth.strategies.approach.lift_over", refuse)
