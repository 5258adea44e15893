"""Replay an AL program on a task: a nominal run and Monte Carlo trials in sampled true worlds.

:func:`replay` parses the program (syntax errors raise :class:`~synth.exceptions.ALSyntaxError`),
binds the task's world to AL names (:mod:`synth.codegen.binding`), and runs it on a
:class:`~synth.replay.machine.ReplayMachine`:

* once in the *nominal* world, where the truth equals the program's beliefs (every object at its
  nominal pose, no hand positioning error);
* ``trials`` times in worlds sampled from the task's uncertainty (:mod:`synth.replay.truth`);
  an object located by contacts is drawn from its contacts (:mod:`synth.replay.located`), not
  from the pose and block the planner derived for it.

**Seeds.** Trial i draws from ``np.random.SeedSequence(seed, spawn_key=(i,))`` — the i-th child
of ``SeedSequence(seed).spawn(trials)`` — split again into one stream for the world and one for
the hand errors. A trial's result depends only on (program, task, seed, i): the same for any
number of workers and any order of completion.

**Parallelism.** With ``workers > 1`` the trials run in a process pool (``spawn`` start
method; each worker parses the program and builds the arm and meshes once), in chunks
(:mod:`synth.replay.trials`); the ``progress`` callback is called in the caller's process as
trials complete, in trial order. The library does no
printing: the CLI draws the progress bar.

**Outcome of a run** (:mod:`synth.replay.report`): ``abort`` when the program aborts, ``error``
for an AL runtime error, ``violation`` when the machine stops it, otherwise ``success`` if the
goal holds (:meth:`ReplayMachine.goal`: the insertion's pin seated in its hole, let go, the
hand clear; a task without an insertion succeeds by running to its end) and ``failure`` if not.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.al import ast
from synth.al.interpreter import Interpreter
from synth.al.parser import parse_program
from synth.codegen.binding import WorldBinding, bind_world
from synth.exceptions import ALRuntimeError, SpecError
from synth.models.arm import Arm, task_arm
from synth.models.arm.collision import SceneCache
from synth.models.believed import believed_graph
from synth.models.graph import AttributeGraph, pose_to_se3
from synth.models.loader import load_task
from synth.models.park import nominal_environment, park_configuration
from synth.models.spec import TaskSpec
from synth.models.uncertainty import Distribution
from synth.models.workcell import WorkcellModel
from synth.replay.machine import ReplayMachine, ReplayOptions, ViolationStop
from synth.replay.report import MonteCarloReport, Outcome, ReplayReport, RunReport
from synth.replay.tally import TrialTally
from synth.replay.trials import TrialPool, deferred_interrupts, iter_trials, job_for
from synth.replay.truth import HandErrors, TrueWorld, nominal_world, sample_world
from synth.seeds import trial_seed

__all__ = [
    "ReplayContext",
    "TrialRecord",
    "TrialSink",
    "machine_for",
    "replay_context",
    "replay_graph",
    "replay_one",
    "replay_program",
    "run_machine",
    "run_nominal",
    "run_trial",
    "run_world",
    "summarise",
    "trial_errors",
    "trial_record",
    "trial_seed",
    "trial_world",
    "world_errors",
]

Progress = Callable[[int, int], None]
"""``progress(done, total)``: trials finished so far, out of ``total``."""


@dataclass(frozen=True, eq=False)
class ReplayContext:
    """Everything a run needs, built once per process.

    The parsed program, the task, its world binding, the arm, the workcell's solids, the park
    pose [m], the arm's configuration there (the planner's start,
    :func:`synth.models.park.park_configuration`) and the machine's options.
    """

    program: ast.Program
    spec: TaskSpec
    graph: AttributeGraph
    binding: WorldBinding
    arm: Arm
    workcell: WorkcellModel
    park: pin.SE3
    q_park: NDArray[np.float64]
    options: ReplayOptions
    scenes: SceneCache = field(default_factory=SceneCache)
    """Collision scenes shared by this context's runs (moved to each trial's poses)."""


def replay_context(
    program_text: str,
    task: TaskSpec | str | Path,
    *,
    filename: str = "<al>",
    base_dir: str | Path | None = None,
    options: ReplayOptions | None = None,
    distribution: Distribution | None = None,
) -> ReplayContext:
    """Parse the program and build the task's model (raises ALSyntaxError, SpecError, ...).

    ``task`` is a spec or a task file; URDF paths resolve against ``base_dir`` (default: the
    task file's directory, or the working directory for a spec). ``distribution`` replaces
    every error block's own (:meth:`~synth.models.spec.TaskSpec.with_distribution`).
    """
    program = parse_program(program_text, filename=filename)
    if isinstance(task, TaskSpec):
        spec = task
    else:
        spec = load_task(task)
        if base_dir is None:
            base_dir = Path(task).resolve().parent
    manipulator = spec.manipulator
    if manipulator is None:
        raise SpecError("manipulator", "the replay needs the task's manipulator (arm and park)")
    arm = task_arm(spec, base_dir)
    park = pose_to_se3(manipulator.park.pose)
    graph = replay_graph(spec, distribution)
    q_park = park_configuration(
        arm, park, nominal_environment(graph, arm), manipulator.park.al_name
    )
    return ReplayContext(
        program=program,
        spec=graph.spec,
        graph=graph,
        binding=bind_world(graph),
        arm=arm,
        workcell=WorkcellModel(graph, [arm.world_from_base.translation]),
        park=park,
        q_park=q_park,
        options=options or ReplayOptions(),
    )


def replay_graph(spec: TaskSpec, distribution: Distribution | None = None) -> AttributeGraph:
    """The graph a replay runs in: the program's beliefs, and the task's contacts.

    Its frames are those of :func:`~synth.models.believed.believed_graph` — an object located by
    contacts at the pose the planner derived, with the derived block: what the program was
    planned with and what its names are bound to — every block's distribution replaced by
    ``distribution``. It keeps the task's ``contacts``, from which
    :func:`~synth.replay.truth.sample_world` draws the true pose of every located object; its
    derived block only measures each trial's error against the belief. Building it again from
    its own spec gives the same graph (the contacts are located again).
    """
    believed = believed_graph(spec).spec
    if distribution is not None:
        believed = believed.with_distribution(distribution)
    if spec.contacts:
        believed = believed.model_copy(update={"contacts": spec.contacts})
    return AttributeGraph(believed)


def machine_for(context: ReplayContext, world: TrueWorld, hand_errors: HandErrors) -> ReplayMachine:
    """A fresh machine in ``world``: the hand at the park pose, every pin where it truly is."""
    workcell = context.workcell.place(world)
    pins = {frame: world.pose(frame) for frame in workcell.pins}
    return ReplayMachine(
        context.arm,
        workcell,
        pins,
        context.q_park,
        hand_errors,
        context.options,
        scenes=context.scenes,
    )


def run_machine(context: ReplayContext, machine: ReplayMachine) -> tuple[RunReport, Interpreter]:
    """Run the program on ``machine``; the run's report and the interpreter (its beliefs).

    The report carries the hand errors the run drew, each with its motion's line.
    """
    budget = context.options
    interpreter = context.binding.interpreter(
        machine,
        max_statements=budget.max_statements,
        max_time=budget.max_time,
        max_wall_time=budget.max_wall_time,
    )
    report = _outcome(context, machine, interpreter)
    return replace(report, hand_errors=tuple(machine.hand_errors.draws)), interpreter


def _outcome(context: ReplayContext, machine: ReplayMachine, interpreter: Interpreter) -> RunReport:
    """Run the program to its end, or to what stopped it: the run's report."""
    try:
        result = interpreter.run(context.program)
    except ViolationStop as stop:
        v = stop.violation
        return RunReport(
            "violation",
            f"{v.kind}: {v.detail}",
            v.line,
            machine.time(),
            interpreter.statements,
            tuple(machine.violations),
        )
    except ALRuntimeError as error:
        return RunReport("error", error.problem, error.line, machine.time(), interpreter.statements)
    if result.abort is not None:
        return RunReport(
            "abort", result.abort.message, result.abort.line, result.time, result.statements
        )
    steps = context.spec.steps
    if not steps:
        return RunReport(
            "success", "the program ran to its end", None, result.time, result.statements
        )
    # Every step's pin must stand seated in its hole at the end (a sequence: each one named).
    verdicts = [
        machine.goal(context.graph.resolve(s.pin), context.graph.resolve(s.hole)) for s in steps
    ]
    outcome: Outcome = "success" if all(ok for ok, _ in verdicts) else "failure"
    why = "; ".join(w for _, w in verdicts)
    unmet = next(
        (
            context.graph.al_names[context.graph.resolve(s.pin)]
            for s, (ok, _) in zip(steps, verdicts, strict=True)
            if not ok
        ),
        None,
    )
    return RunReport(outcome, why, None, result.time, result.statements, unmet=unmet)


def run_world(context: ReplayContext, world: TrueWorld, hand_errors: HandErrors) -> RunReport:
    """Run the program once in ``world`` with ``hand_errors``; the run's report."""
    return run_machine(context, machine_for(context, world, hand_errors))[0]


def run_nominal(context: ReplayContext) -> RunReport:
    """The run in the believed world (no errors anywhere)."""
    return run_world(context, nominal_world(context.graph), HandErrors.none())


def trial_world(context: ReplayContext, seed: int, index: int) -> tuple[TrueWorld, HandErrors]:
    """Trial ``index``'s sampled world and hand errors, from :func:`trial_seed`."""
    world_seed, hand_seed = trial_seed(seed, index).spawn(2)
    world = sample_world(context.graph, np.random.default_rng(world_seed))
    manipulator = context.spec.manipulator
    assert manipulator is not None
    hand = HandErrors(manipulator.hand_error, np.random.default_rng(hand_seed))
    return world, hand


def run_trial(context: ReplayContext, seed: int, index: int) -> RunReport:
    """Monte Carlo trial ``index``: a sampled world and hand errors from :func:`trial_seed`."""
    return run_world(context, *trial_world(context, seed, index))


def summarise(runs: Iterable[RunReport], seed: int) -> MonteCarloReport:
    """Outcome counts (in ``OUTCOMES`` order) and time mean / 95th percentile [s].

    The runs are tallied as they come (:class:`~synth.replay.tally.TrialTally`), so ``runs``
    may be a stream.
    """
    tally = TrialTally(kept_runs=0)
    for run in runs:
        tally.add(run)
    return tally.report(seed)


def trial_errors(context: ReplayContext, seed: int, index: int) -> dict[str, dict[str, float]]:
    """The error parameters trial ``index`` sampled, per perturbed frame [m, rad].

    The same draw as :func:`run_trial` (the world's stream of :func:`trial_seed`), so a failing
    trial can be reported with the errors that made it fail.
    """
    return world_errors(context.graph, seed, index)


def world_errors(graph: AttributeGraph, seed: int, index: int) -> dict[str, dict[str, float]]:
    """:func:`trial_errors` from the sampled graph alone (:func:`replay_graph`), no arm built."""
    world_seed, _ = trial_seed(seed, index).spawn(2)
    world = sample_world(graph, np.random.default_rng(world_seed))
    return {frame: dict(values) for frame, values in world.parameters.items()}


@dataclass(frozen=True)
class TrialRecord:
    """One Monte Carlo trial, for diagnosis: its index, seed, sampled errors and its run.

    ``errors`` maps every perturbed frame to the error parameters trial ``index`` drew for it
    [m, rad] (:func:`trial_errors`); ``run`` is the trial's report, with the hand's
    positioning error at each target (``run.hand_errors``, drawn per motion target).
    """

    index: int
    seed: int
    errors: dict[str, dict[str, float]]
    run: RunReport

    def to_json(self) -> dict[str, Any]:
        """The record as JSON (SI units).

        ``{"index", "seed", "errors", "outcome", "line", "message", "time", "statements",
        "violations", "hand_errors"}``; ``hand_errors`` lists ``{"line", "target", "x", …,
        "rz"}`` per target, in the order the run moved.
        """
        return {
            "index": self.index,
            "seed": self.seed,
            "errors": self.errors,
            **self.run.to_json(),
            "hand_errors": [draw.to_json() for draw in self.run.hand_errors],
        }


TrialSink = Callable[[TrialRecord], None]
"""``on_trial(record)``: called for every trial (or every failing one), in trial order."""


def trial_record(context: ReplayContext, seed: int, index: int, run: RunReport) -> TrialRecord:
    """The :class:`TrialRecord` of trial ``index``'s ``run`` (its errors drawn again)."""
    return TrialRecord(index, seed, trial_errors(context, seed, index), run)


def replay_one(
    program_text: str,
    task: TaskSpec | str | Path,
    index: int,
    *,
    seed: int = 0,
    filename: str = "<al>",
    base_dir: str | Path | None = None,
    options: ReplayOptions | None = None,
    distribution: Distribution | None = None,
) -> TrialRecord:
    """Run Monte Carlo trial ``index`` of ``seed`` alone.

    The same world and hand errors as in a full :func:`replay`: a trial depends only on the
    program, the task, the seed and its index.
    """
    if index < 0:
        raise ValueError(f"the trial index must be ≥ 0, got {index}")
    # build_context resolves a task file's URDF paths against its directory itself
    context = replay_context(
        program_text,
        task,
        filename=filename,
        base_dir=base_dir,
        options=options,
        distribution=distribution,
    )
    return trial_record(context, seed, index, run_trial(context, seed, index))


def replay_program(
    program_text: str,
    task: TaskSpec | str | Path,
    *,
    trials: int = 0,
    seed: int = 0,
    workers: int = 1,
    filename: str = "<al>",
    base_dir: str | Path | None = None,
    options: ReplayOptions | None = None,
    progress: Progress | None = None,
    distribution: Distribution | None = None,
    on_trial: TrialSink | None = None,
    failures_only: bool = False,
    client: Any | None = None,
) -> ReplayReport:
    """Replay ``program_text`` on ``task``: the nominal run and ``trials`` Monte Carlo trials.

    ``seed`` seeds the trials (:func:`trial_seed`); ``workers`` processes run them (1: in this
    process); ``distribution`` overrides the task's sampling distributions. Raises
    ALSyntaxError for a program that does not parse and SpecError (or another
    :class:`~synth.exceptions.SynthError`) for an unusable task.

    ``on_trial`` receives a :class:`TrialRecord` per trial in trial order as it completes
    (only the failing ones with ``failures_only``), so a caller can stream them: the replay
    itself keeps no more than its bounded tally. A ``KeyboardInterrupt`` (Ctrl-C) stops the
    trials at once, workers included: the report then has the trials completed so far and
    ``interrupted`` set.

    ``client``, a ``distributed.Client``, runs the trials on its Dask cluster instead of
    ``workers`` local processes (:mod:`synth.replay.cluster`): the same report.
    """
    if trials < 0:
        raise ValueError(f"trials must be ≥ 0, got {trials}")
    if isinstance(task, str | Path) and base_dir is None:
        base_dir = Path(task).resolve().parent
    context = replay_context(
        program_text,
        task,
        filename=filename,
        base_dir=base_dir,
        options=options,
        distribution=distribution,
    )
    nominal = run_nominal(context)
    job = job_for(program_text, context, filename=filename, base_dir=base_dir, options=options)
    tally = TrialTally()  # bounded memory, whatever ``trials`` is
    interrupted = False
    with (
        TrialPool(1 if client is not None else min(workers, max(trials, 1))) as pool,
        deferred_interrupts() as stop,
    ):
        if client is not None:
            from synth.replay.cluster import iter_trials_on

            runs = iter_trials_on(client, job, seed, trials, stop)
        else:
            runs = iter_trials(job, context, seed, trials, pool, stop)
        try:
            for run in runs:
                if on_trial is not None and not (failures_only and run.success):
                    on_trial(trial_record(context, seed, tally.count, run))
                tally.add(run)
                if progress is not None:
                    progress(tally.count, trials)
        except KeyboardInterrupt:
            interrupted = True
            pool.abort()
        finally:
            runs.close()  # cancels what is still queued (pool or cluster)
    return ReplayReport(
        filename,
        context.spec.name,
        nominal,
        tally.report(seed),
        tuple(tally.runs),
        interrupted=interrupted,
        planned=trials,
    )


"""The entry point the HTTP service looks up (``server/service.py``)."""
