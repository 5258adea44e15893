"""synth: task-level synthesis of AL manipulator programs, after R. H. Taylor (1976).

Data flow (see ``docs/design.md``): task YAML → :mod:`synth.models` → :mod:`synth.errors` →
:mod:`synth.strategies` → :mod:`synth.codegen` → :mod:`synth.al` / :mod:`synth.replay`.

The pipeline as a Python API (``docs/python-api.md``); each name is imported on first use, so
``import synth`` stays light:

* :func:`load_task` — a task file to a validated :class:`TaskSpec` (SI units);
* :func:`synthesize` with :class:`SynthesisOptions` (:class:`PlanOptions`,
  :class:`ProofOptions`) — the one call from a task to a proven program: a
  :class:`Synthesis` (or :class:`SequenceSynthesis` for several insertions);
* :func:`believed_graph`, :func:`plan_task` (→ :class:`PlanResult`, its
  :class:`PinInHoleStrategy`), :func:`emit_program` — the stages one by one;
* :func:`replay_program` (→ :class:`ReplayReport`) — run AL text on the task's simulated arm
  (:func:`synth.replay.run.replay_program`; ``synth.replay`` itself is the replay's package);
* :func:`export_trajectory` — the nominal run's joint trajectory (ROS YAML or CSV);
* :class:`SynthError` — the base of every error a user can cause.
"""

from __future__ import annotations

import importlib

TYPE_CHECKING = False  # not typing's: ``import synth`` stays free of ``typing`` (mypy knows it)

__version__ = "0.1.0"

_API: dict[str, str] = {
    "load_task": "synth.models.loader",
    "TaskSpec": "synth.models.spec",
    "synthesize": "synth.pipeline",
    "SynthesisOptions": "synth.pipeline",
    "Synthesis": "synth.pipeline",
    "SequenceSynthesis": "synth.pipeline",
    "CandidateProof": "synth.pipeline",
    "PlanOptions": "synth.strategies.options",
    "plan_task": "synth.strategies.planner",
    "PlanResult": "synth.strategies.records",
    "PinInHoleStrategy": "synth.strategies.records",
    "Rejection": "synth.strategies.records",
    "believed_graph": "synth.models.believed",
    "emit_program": "synth.codegen.emitter",
    "ProofOptions": "synth.replay.proof",
    "Proof": "synth.replay.proof",
    "replay_program": "synth.replay.run",
    "ReplayReport": "synth.replay.report",
    "RunReport": "synth.replay.report",
    "export_trajectory": "synth.replay.trajectory",
    "Trajectory": "synth.replay.trajectory",
    "SynthError": "synth.exceptions",
    "NoStrategyError": "synth.exceptions",
    "SpecError": "synth.exceptions",
}

__all__ = [
    "CandidateProof",
    "NoStrategyError",
    "PinInHoleStrategy",
    "PlanOptions",
    "PlanResult",
    "Proof",
    "ProofOptions",
    "Rejection",
    "ReplayReport",
    "RunReport",
    "SequenceSynthesis",
    "SpecError",
    "SynthError",
    "Synthesis",
    "SynthesisOptions",
    "TaskSpec",
    "Trajectory",
    "believed_graph",
    "emit_program",
    "export_trajectory",
    "load_task",
    "plan_task",
    "replay_program",
    "synthesize",
]

if TYPE_CHECKING:
    from typing import Any

    from synth.codegen.emitter import emit_program
    from synth.exceptions import NoStrategyError, SpecError, SynthError
    from synth.models.believed import believed_graph
    from synth.models.loader import load_task
    from synth.models.spec import TaskSpec
    from synth.pipeline import (
        CandidateProof,
        SequenceSynthesis,
        Synthesis,
        SynthesisOptions,
        synthesize,
    )
    from synth.replay.proof import Proof, ProofOptions
    from synth.replay.report import ReplayReport, RunReport
    from synth.replay.run import replay_program
    from synth.replay.trajectory import Trajectory, export_trajectory
    from synth.strategies.options import PlanOptions
    from synth.strategies.planner import plan_task
    from synth.strategies.records import PinInHoleStrategy, PlanResult, Rejection


def __getattr__(name: str) -> Any:
    """Import an API name from its module on first use (PEP 562)."""
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module 'synth' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """The module's names, the lazily imported API among them."""
    return sorted([*globals(), *_API])
