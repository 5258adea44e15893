"""The one pipeline from a task to a proven program: believed graph → plan → program → proof.

:func:`synthesize` is what ``synth plan``, the HTTP service, ``scripts/regen_golden.py``, the
benchmarks and the end-to-end tests call; none of them composes the stages itself.

1. The believed graph (:func:`~synth.models.believed.believed_graph`): contact-located objects
   where their contacts put them — the world the planner plans in and the emitter declares
   (the replay draws their true poses from the contacts themselves).
2. Best-first planning (:func:`~synth.strategies.planner.plan_task`, seed §4.2–4.6).
3. The chosen strategy's AL program (:func:`~synth.codegen.emitter.emit_program`).
4. Its proof (:func:`~synth.replay.proof.prove`): the nominal replay and a sequential Monte
   Carlo test. A candidate whose proof fails is rejected with the replay's reason, and the
   planner's next best candidate is emitted and proven in turn. Only a proven program leaves:
   when none is proven, :class:`~synth.exceptions.NoStrategyError` names the root cause.

The proof's trials run in one :class:`~synth.replay.trials.TrialPool` for the whole call, so
proving a second candidate does not start the workers again.

A task with several insertions (``insertions:``) goes the same way as a whole
(:class:`SequenceSynthesis`): :func:`~synth.strategies.sequence.plan_sequence` plans the steps,
each step's candidate accepted by the nominal replay of its own program from where the step
before left the arm (which gives the next step's start); the steps' programs and the
corrections between them become one program (:func:`~synth.codegen.sequence.emit_sequence`),
proven as a whole: nominal run and Monte Carlo over every step's pin, in the task's own
uncertainty, never the planner's reduced one.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from synth.codegen.emitter import emit_program
from synth.codegen.sequence import SequenceStep, emit_sequence
from synth.codegen.views import missed_message
from synth.exceptions import NoStrategyError
from synth.models.believed import believed_graph
from synth.models.graph import AttributeGraph
from synth.models.insertion import exceeds_lead
from synth.models.loader import load_task
from synth.models.spec import TaskSpec
from synth.replay.proof import Proof, ProofOptions, prove
from synth.replay.run import machine_for, run_machine
from synth.replay.run import replay_context as replay_context
from synth.replay.trials import TrialPool
from synth.replay.truth import HandErrors, nominal_world
from synth.strategies.causes import root_cause
from synth.strategies.options import PlanOptions
from synth.strategies.planner import plan_task
from synth.strategies.records import PinInHoleStrategy, PlanResult, Rejection
from synth.strategies.sequence import SequencePlan, StepCheck, plan_sequence

__all__ = [
    "CandidateProof",
    "SequenceSynthesis",
    "Synthesis",
    "SynthesisOptions",
    "synthesize",
]

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
    reuse: bool = True
    """A sequence's steps use what earlier seats taught (False: each step alone, no
    corrections in the program; for comparisons)."""


@dataclass(frozen=True)
class CandidateProof:
    """One candidate's program and proof, in the order the pipeline proved them."""

    candidate: str
    proof: Proof
    refuted: str | None = None
    """``dr_ok`` when the proof passed but a trial missed the hole with Δr_ok wider than the
    parts' lead: the candidate was planned again at the lead (:func:`_missed_by_gaps`)."""

    def to_json(self) -> dict[str, Any]:
        """``{"candidate", "proof", "refuted"}``."""
        return {"candidate": self.candidate, "proof": self.proof.to_json(), "refuted": self.refuted}


@dataclass(frozen=True, eq=False, kw_only=True)
class _Proven:
    """What every synthesis leaves: the task, its believed world, the program and its proofs.

    ``program`` is the text to write (with the preamble when asked); ``attempts`` every
    program proven, the failed ones first, the last being the written program's
    (:attr:`proof`); ``graph`` the believed world the program was planned in.
    """

    task: TaskSpec
    graph: AttributeGraph
    program: str
    attempts: tuple[CandidateProof, ...]

    @property
    def proof(self) -> Proof:
        """The written program's proof: the last one tried, the one that passed."""
        return self.attempts[-1].proof

    @property
    def fallback(self) -> str | None:
        """Why the written program is a fallback, or None when it is the plan's first choice.

        A fallback is a program whose proof passed with a trial that missed the hole by the
        search's gaps (:func:`_missed_by_gaps`), written because everything planned again at
        the parts' lead was refused: it may miss a little more often than its proof says.
        """
        written = self.attempts[-1]
        if written.refuted != "dr_ok":
            return None
        failure = written.proof.first_failure
        missed = "" if failure is None else f" (trial {failure.index} missed the hole)"
        return (
            f"{written.candidate} is written as the fallback: its proof passed{missed}, but "
            "every plan at the parts' lead was refused (see Rejected); its search, spaced by "
            "the task's Δr_ok, may leave gaps the hole can sit in"
        )


@dataclass(frozen=True, eq=False, kw_only=True)
class Synthesis(_Proven):
    """A proven single-insertion program and the plan that chose it."""

    plan: PlanResult

    @property
    def pictured(self) -> tuple[PinInHoleStrategy, AttributeGraph, str]:
        """The strategy, world and step (none) the plan picture draws: the chosen one."""
        return self.plan.strategy, self.graph, ""

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
            "fallback": self.fallback,
            "attempts": [a.to_json() for a in self.attempts],
        }


def _task(task: TaskSpec | str | Path, base_dir: str | Path | None) -> tuple[TaskSpec, Path | None]:
    if isinstance(task, TaskSpec):
        return task, None if base_dir is None else Path(base_dir)
    path = Path(task)
    return load_task(path), Path(base_dir) if base_dir is not None else path.resolve().parent


@dataclass(frozen=True, eq=False, kw_only=True)
class SequenceSynthesis(_Proven):
    """A proven assembly sequence: its plan, the one program and that program's proof."""

    sequence: SequencePlan

    @property
    def pictured(self) -> tuple[PinInHoleStrategy, AttributeGraph, str]:
        """The strategy, world and step the plan picture draws: the first step's, in its world.

        The step is named in the picture's title (``step 1 of 2 (PIN1 into PH1)``): it drew
        the first step's strategy alone and did not say so.
        """
        first = self.sequence.steps[0]
        step = f"step 1 of {len(self.sequence.steps)} ({first.insertion.pin} into "
        return first.strategy, believed_graph(first.task), step + f"{first.insertion.hole})"

    def to_json(self) -> dict[str, Any]:
        """``synth plan --json`` of a sequence: one record per step, the program, the proof."""
        steps = []
        for s in self.sequence.steps:
            errors = s.strategy.errors
            record: dict[str, Any] = {
                "step": s.index + 1,
                "pin": s.insertion.pin,
                "hole": s.insertion.hole,
                "expected_time": s.time,
                "strategy": s.strategy.to_json(),
                "errors": None if errors is None else errors.to_json(),
                "reuse": None,
                "correction_declined": None,
            }
            if isinstance(s.alone, str):
                record["without_reuse"] = {"refused": s.alone}
            elif s.alone is not None:
                before = s.alone.strategy.errors
                record["without_reuse"] = {
                    "expected_time": s.alone.strategy.expected_time,
                    "errors": None if before is None else before.to_json(),
                    "search": s.alone.strategy.search is not None,
                    "tap": s.alone.strategy.tap is not None,
                }
                record["saved"] = s.saved
            if s.declined is not None:
                record["correction_declined"] = {
                    "part": s.declined.part_al,
                    "located_by": s.declined.hole_al,
                    "next_step_faster_by": (
                        None if s.declined_saving == float("inf") else s.declined_saving
                    ),
                }
            if s.knowledge is not None:
                k = s.knowledge
                record["reuse"] = {
                    "part": k.part_al,
                    "located_by": k.hole_al,
                    "corrected_axes": list(k.corrected),
                    "reading_error": k.epsilon,
                    "before": {p: [b.lo, b.hi] for p, b in k.before.bounds().items()},
                    "after": {p: [b.lo, b.hi] for p, b in k.after.bounds().items()},
                }
            steps.append(record)
        return {
            "task": self.task.name,
            "order": self.sequence.order,
            "expected_time": self.sequence.expected_time,
            "orders_expanded": self.sequence.expanded,
            "steps_planned": self.sequence.planned,
            "steps": steps,
            "program": self.program,
            "proof": self.proof.to_json(),
            "fallback": self.fallback,
        }


def synthesize(
    task: TaskSpec | str | Path,
    options: SynthesisOptions | None = None,
    *,
    base_dir: str | Path | None = None,
    progress: Progress | None = None,
) -> Synthesis | SequenceSynthesis:
    """Take ``task`` (a spec or a task file) to a proven program (see the module docstring).

    ``base_dir`` resolves a URDF arm's relative paths (default: the task file's directory).
    Raises :class:`~synth.exceptions.NoStrategyError` when no candidate is proven (its first
    line names the root cause), SpecError for an unusable task.
    """
    opts = options or SynthesisOptions()
    spec, where = _task(task, base_dir)
    if len(spec.steps) == 1 and spec.insertion is None:
        spec = spec.step(spec.steps[0])  # a one-step list is a single insertion
    if spec.is_sequence:
        return _synthesize_sequence(spec, opts, where, progress)
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
            gaps = _missed_by_gaps(proof, strategy)
            attempts.append(CandidateProof(strategy.name, proof, "dr_ok" if gaps else None))
            if proof.passed:
                programs[strategy.name] = body
                if gaps is None:
                    return None
                return Rejection(
                    strategy.name, gaps, cause="proof", stage="proof", refuted="dr_ok", proven=True
                )
            return Rejection(
                strategy.name,
                proof.reason(),
                cause="proof",
                stage="proof",
                refuted=_refuted(proof, strategy),
            )

        plan = plan_task(spec, options=opts.plan, base_dir=where, accept=accept)
    chosen = plan.strategy
    program = programs[chosen.name]
    attempts = _written_last(attempts, chosen.name)
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


MAX_SEQUENCE_ATTEMPTS = 4
"""Sequences proven before giving up: after a failed proof the step it failed in gives up its
strategy and the sequence is planned again."""


@dataclass(frozen=True)
class StepBan:
    """A step's strategy refused for the proof of its sequence, and why.

    The sequence failed its proof in that step, or passed it with a search that missed by its
    gaps. ``refuted``: the belief the proof refuted (:func:`_refuted`); ``reason``: how it
    failed, the proof's reason (its first failing trial, line and sampled errors; empty for a
    proof that passed).
    """

    refuted: str | None
    reason: str


def _step_check(base_dir: Path | None, banned: dict[int, dict[str, StepBan]]) -> StepCheck:
    """Accept a step's strategy by the nominal replay of its program; return where it ends.

    Strategies in ``banned[step]`` failed a proof of the whole sequence and are refused, with
    their :class:`StepBan`.
    """

    def check(
        index: int,
        task: TaskSpec,
        q_start: NDArray[np.float64] | None,
        strategy: PinInHoleStrategy,
    ) -> tuple[Rejection | None, NDArray[np.float64] | None]:
        ban = banned.get(index, {}).get(strategy.name)
        if ban is not None:
            reason = "the sequence holding it failed its replay proof in this step"
            if ban.reason:  # a proof that passed but missed by gaps has no reason
                reason = f"{reason} ({ban.reason})"
            rejection = Rejection(
                strategy.name, reason, cause="proof", stage="proof", refuted=ban.refuted
            )
            return rejection, None
        graph = believed_graph(task)
        body = emit_program(strategy, graph)
        context = replay_context(body, task, base_dir=base_dir)
        if q_start is not None:
            context = dataclasses.replace(context, q_park=np.array(q_start, dtype=float))
        machine = machine_for(context, nominal_world(context.graph), HandErrors.none())
        report, _ = run_machine(context, machine)
        if report.outcome != "success":
            where = f" at AL line {report.line}" if report.line else ""
            reason = f"nominal replay of the step: {report.outcome}{where}: {report.message}"
            return Rejection(strategy.name, reason, cause="proof", stage="proof"), None
        return None, machine.configuration

    return check


def _missed_by_gaps(proof: Proof, strategy: PinInHoleStrategy) -> str | None:
    """Why a *passed* proof refuted ``strategy``'s Δr_ok, or None.

    A trial that aborts because the pin missed its hole, under a Δr_ok wider than the parts'
    lead, is no bad luck: the search was spaced by Δr_ok, the replay captures within the lead,
    so the pattern leaves gaps the hole can sit in (benchmarks/variants.py --seed 11: three
    programs proven 99 of 100 replayed 193–198 of 200 afresh, every failure such a miss).
    """
    if not proof.passed or proof.first_failure is None or not exceeds_lead(strategy):
        return None
    if _refuted(proof, strategy) != "dr_ok":
        return None
    assert strategy.lead is not None
    return (
        f"proven ({proof.successes} of {proof.trials} trials), but "
        f"{proof.first_failure.describe()}: Δr_ok = {100 * strategy.dr_ok:.3g} cm is wider than "
        f"the parts' lead {100 * strategy.lead:.3g} cm, so the search leaves gaps"
    )


def _written_last(attempts: list[CandidateProof], written: str) -> list[CandidateProof]:
    """``attempts`` with the written program's passed proof moved last (:attr:`_Proven.proof`).

    It is last already unless it was a fallback: proven with a miss, then every candidate
    planned at the lead was refused.
    """
    kept = [a for a in attempts if a.candidate == written and a.proof.passed][-1:]
    return [a for a in attempts if a not in kept] + kept


def _refuted(proof: Proof, strategy: PinInHoleStrategy) -> str | None:
    """``dr_ok`` when the failed run aborted because the pin missed the hole, else None."""
    failed = proof.nominal if proof.nominal.outcome != "success" else proof.first_failure
    if failed is None or failed.outcome != "abort":
        return None
    return "dr_ok" if failed.message.startswith(missed_message(strategy)) else None


def _failing_line(proof: Proof) -> int | None:
    if proof.nominal.outcome != "success":
        return proof.nominal.line
    return None if proof.first_failure is None else proof.first_failure.line


def _failing_pin(proof: Proof) -> str | None:
    """The pin whose goal the failed run did not meet (a run that completed has no AL line)."""
    if proof.nominal.outcome != "success":
        return proof.nominal.unmet
    return None if proof.first_failure is None else proof.first_failure.unmet


def _step_at(program: str, line: int | None, count: int) -> int | None:
    """Which step (0-based, in execution order) the program's ``line`` belongs to."""
    if line is None:
        return None
    starts = [
        n for n, text in enumerate(program.splitlines(), start=1) if text.startswith("{ STEP ")
    ]
    if len(starts) != count:
        return None
    before = [k for k, start in enumerate(starts) if start <= line]
    return before[-1] if before else None


def _synthesize_sequence(
    spec: TaskSpec, opts: SynthesisOptions, where: Path | None, progress: Progress | None
) -> SequenceSynthesis:
    proof_options = opts.proof or ProofOptions.for_task(spec)
    graph = believed_graph(spec)
    banned: dict[int, dict[str, StepBan]] = {}
    attempts: list[CandidateProof] = []
    plan_options = opts.plan
    fallback: SequenceSynthesis | None = None  # proven, but a step's search missed by gaps
    with TrialPool(proof_options.workers) as pool:
        for attempt in range(1, MAX_SEQUENCE_ATTEMPTS + 1):
            try:
                sequence = plan_sequence(
                    spec,
                    _step_check(where, banned),
                    options=plan_options,
                    base_dir=where,
                    reuse=opts.reuse,
                )
            except NoStrategyError:
                if fallback is None:
                    raise
                break  # nothing planned at the lead: the sequence proven with a miss stands
            steps = [
                SequenceStep(
                    graph.al_names[graph.resolve(s.insertion.pin)],
                    graph.al_names[graph.resolve(s.insertion.hole)],
                    emit_program(s.strategy, believed_graph(s.task)),
                    # after the last seat nothing is left to correct for
                    s.knowledge if k < len(sequence.steps) else None,
                )
                for k, s in enumerate(sequence.steps, start=1)
            ]
            program = emit_sequence(steps, graph, sequence.expected_time)
            label = f"sequence {attempt}: " + ", ".join(s.strategy.name for s in sequence.steps)
            report = None if progress is None else _named(progress, label)
            proof = prove(program, spec, proof_options, base_dir=where, pool=pool, progress=report)
            failed = _step_at(program, _failing_line(proof), len(sequence.steps))
            if failed is None:  # a goal failure has no AL line: blame its unseated pin's step
                unmet = _failing_pin(proof)
                failed = next((k for k, s in enumerate(steps) if s.pin == unmet), None)
            step = None if failed is None else sequence.steps[failed]
            gaps = None if step is None else _missed_by_gaps(proof, step.strategy)
            attempts.append(CandidateProof(label, proof, "dr_ok" if gaps else None))
            if proof.passed:
                if opts.preamble:
                    program = emit_sequence(steps, graph, sequence.expected_time, preamble=True)
                written = SequenceSynthesis(
                    task=spec,
                    graph=graph,
                    sequence=sequence,
                    program=program,
                    attempts=tuple(attempts),
                )
                if gaps is None:
                    return written
                fallback = fallback or written
            if step is None:
                break
            refuted = _refuted(proof, step.strategy)
            banned.setdefault(step.index, {})[step.strategy.name] = StepBan(refuted, proof.reason())
            if refuted == "dr_ok":  # a miss: every step's search at its parts' lead from now on
                plan_options = dataclasses.replace(plan_options, at_lead=True)
    if fallback is not None:
        label = fallback.attempts[-1].candidate
        return dataclasses.replace(fallback, attempts=tuple(_written_last(attempts, label)))
    rejections = tuple(
        Rejection(a.candidate, a.proof.reason(), cause="proof", stage="proof") for a in attempts
    )
    raise NoStrategyError(spec.name, rejections, root_cause(list(rejections)))
