"""The one pipeline from a task to a proven program: believed graph → plan → program → proof.

:func:`synthesize` is what ``synth plan``, the HTTP service, ``scripts/regen_golden.py``, the
benchmarks and the end-to-end tests call; none of them composes the stages itself.

1. The believed graph (:func:`~synth.errors.locate.believed_graph`): contact-located objects
   where their contacts put them — the world the planner plans in, the emitter declares and
   the replay samples true worlds around.
2. Best-first planning (:func:`~synth.strategies.planner.plan_task`, seed §4.2–4.6).
3. The chosen strategy's AL program (:func:`~synth.codegen.emitter.emit_program`).
4. Its proof (:func:`~synth.replay.proof.prove`): the nominal replay and a sequential Monte
   Carlo test. A candidate whose proof fails is rejected with the replay's reason, and the
   planner's next best candidate is emitted and proven in turn. Only a proven program leaves:
   when none is proven, :class:`~synth.exceptions.NoStrategyError` names the root cause.

The proof's trials run in one :class:`~synth.replay.trials.TrialPool` for the whole call, so
proving a second candidate does not start the workers again.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from synth.codegen.emitter import emit_program
from synth.errors.locate import believed_graph
from synth.models.graph import AttributeGraph
from synth.models.loader import load_task
from synth.models.spec import TaskSpec
from synth.replay.proof import Proof, ProofOptions, prove
from synth.replay.trials import TrialPool
from synth.strategies.options import PlanOptions
from synth.strategies.planner import plan_task
from synth.strategies.records import PinInHoleStrategy, PlanResult, Rejection

__all__ = ["CandidateProof", "Synthesis", "SynthesisOptions", "synthesize"]

Progress = Callable[[str, int, int], None]
"""``progress(candidate, done, budget)``: proof trials finished for the candidate named."""


@dataclass(frozen=True)
class SynthesisOptions:
    """Options of :func:`synthesize`: the planner's, the proof's, and the program's preamble.

    ``proof`` None takes the task's own ``proof`` section (:meth:`ProofOptions.for_task`);
    ``preamble`` starts the written program with the task's frame declarations; the proof
    replays the program body, which the replay binds to the task itself.
    """

    plan: PlanOptions = field(default_factory=PlanOptions)
    proof: ProofOptions | None = None
    preamble: bool = False


@dataclass(frozen=True)
class CandidateProof:
    """One candidate's program and proof, in the order the pipeline proved them."""

    candidate: str
    proof: Proof

    def to_json(self) -> dict[str, Any]:
        """``{"candidate", "proof"}``."""
        return {"candidate": self.candidate, "proof": self.proof.to_json()}


@dataclass(frozen=True, eq=False)
class Synthesis:
    """A proven program: the plan that chose it, its text, and the proofs tried.

    ``program`` is the text to write (with the preamble when asked); ``attempts`` every
    candidate proven, the failed ones first, the last being the chosen program's
    (:attr:`proof`); ``graph`` the believed world the program was planned in.
    """

    task: TaskSpec
    graph: AttributeGraph
    plan: PlanResult
    program: str
    attempts: tuple[CandidateProof, ...]

    @property
    def proof(self) -> Proof:
        """The chosen program's proof: the last one tried, the one that passed."""
        return self.attempts[-1].proof

    @property
    def strategy(self) -> PinInHoleStrategy:
        """The chosen strategy."""
        return self.plan.strategy

    def to_json(self) -> dict[str, Any]:
        """The ``synth plan --json`` document: the plan, the program and its proof."""
        return {
            **self.plan.to_json(),
            "program": self.program,
            "proof": self.proof.to_json(),
            "attempts": [a.to_json() for a in self.attempts],
        }


def _task(task: TaskSpec | str | Path, base_dir: str | Path | None) -> tuple[TaskSpec, Path | None]:
    if isinstance(task, TaskSpec):
        return task, None if base_dir is None else Path(base_dir)
    path = Path(task)
    return load_task(path), Path(base_dir) if base_dir is not None else path.resolve().parent


def synthesize(
    task: TaskSpec | str | Path,
    options: SynthesisOptions | None = None,
    *,
    base_dir: str | Path | None = None,
    progress: Progress | None = None,
) -> Synthesis:
    """Take ``task`` (a spec or a task file) to a proven program (see the module docstring).

    ``base_dir`` resolves a URDF arm's relative paths (default: the task file's directory).
    Raises :class:`~synth.exceptions.NoStrategyError` when no candidate is proven (its first
    line names the root cause), SpecError for an unusable task.
    """
    opts = options or SynthesisOptions()
    spec, where = _task(task, base_dir)
    proof_options = opts.proof or ProofOptions.for_task(spec)
    graph = believed_graph(spec)
    attempts: list[CandidateProof] = []
    programs: dict[str, str] = {}
    with TrialPool(proof_options.workers) as pool:
        if proof_options.trials:
            pool.warm()

        def accept(strategy: PinInHoleStrategy) -> Rejection | None:
            body = emit_program(strategy, graph)
            report = None if progress is None else _named(progress, strategy.name)
            proof = prove(body, spec, proof_options, base_dir=where, pool=pool, progress=report)
            attempts.append(CandidateProof(strategy.name, proof))
            if proof.passed:
                programs[strategy.name] = body
                return None
            return Rejection(strategy.name, proof.reason(), cause="proof", stage="proof")

        plan = plan_task(spec, options=opts.plan, base_dir=where, accept=accept)
    chosen = plan.strategy
    program = programs[chosen.name]
    if opts.preamble:
        program = emit_program(chosen, graph, preamble=True)
    return Synthesis(
        task=spec,
        graph=graph,
        plan=plan,
        program=program,
        attempts=tuple(attempts),
    )


def _named(progress: Progress, name: str) -> Callable[[int, int], None]:
    return lambda done, total: progress(name, done, total)
