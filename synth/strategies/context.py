"""What every planning stage shares: the task, its arm, the insertion and the counters.

:func:`build_context` reads the task once (attribute graph, insertion parameters of seed §4.2,
the arm, the park configuration, the pin's depth d_i in its start hole) and makes the root of
the multiple-world assertion base (seed L1800): the facts every hypothetical world of a
candidate strategy starts from. The context also funnels the arm and the bound calls so that a
plan can report how many inverse-kinematics solutions, motion times and LPs it needed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Literal

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.errors.bounds import Interval, bound_linear
from synth.errors.chain import chain_between
from synth.errors.estimate import ErrorReport, estimate_errors
from synth.errors.parameters import ParameterSpace
from synth.exceptions import SpecError
from synth.models.arm import (
    Arm,
    CollisionScene,
    SweepResult,
    motion_time,
    nearest_solution,
    task_arm,
)
from synth.models.believed import believed_graph
from synth.models.graph import AttributeGraph, pose_to_se3
from synth.models.insertion import InsertionParameters, derive, refuse_unprovable
from synth.models.manipulator import HandSpec
from synth.models.park import nominal_environment, park_configuration
from synth.models.spec import WORLD, HoleShape, PinShape, TaskSpec
from synth.models.uncertainty import Uncertainty
from synth.models.world import Fact, World
from synth.strategies.clearance import GrossMotionCheck
from synth.strategies.hypotheses import At, HandError, Holding, InHole, Task, Uncertain
from synth.strategies.options import PlanOptions, hand_openings
from synth.strategies.records import Grasp

Configuration = NDArray[np.float64]
PinEnd = Literal["tip", "head"]


@dataclass
class PlanCounters:
    """Work done by one plan: arm solutions, motion times and error bounds.

    ``bounds`` counts extrema of linear functionals over a parameter set; ``lp`` those of them
    that needed HiGHS (coupled constraints, e.g. a tap measurement) instead of the closed form;
    ``sweeps`` the swept collision checks of gross motions (:mod:`synth.strategies.clearance`).
    Local to one :func:`~synth.strategies.planner.plan_task` call.
    """

    ik: int = 0
    motion_time: int = 0
    bounds: int = 0
    lp: int = 0
    sweeps: int = 0

    def as_dict(self) -> dict[str, int]:
        """The counts for ``PlanResult.counters``."""
        return {
            "ik": self.ik,
            "motion_time": self.motion_time,
            "bounds": self.bounds,
            "lp": self.lp,
            "sweeps": self.sweeps,
        }

    def count_bounds(self, space: ParameterSpace, n: int = 1) -> None:
        """Record ``n`` bound evaluations over ``space`` (LPs unless it is a box)."""
        self.bounds += n
        if not space.is_box:
            self.lp += n


@dataclass(frozen=True, eq=False)
class PlanContext:
    """The inputs shared by the planning stages (see the module docstring).

    ``pin_frame``, ``hole_frame``, ``start_hole`` are frame names; ``pin_al``, ``hole_al``,
    ``hand_al`` AL names. ``d_i`` [m] is how deep the pin sits in its start hole (tip first,
    seed L2036); ``target_end`` says which end goes into the target hole and
    ``pin_from_end`` is that end's frame in the pin frame (z out of the hole once
    inserted). ``q_park`` is where the arm starts: at the park frame, or where the last step
    of a sequence left it (``from_park`` False).
    """

    spec: TaskSpec
    graph: AttributeGraph
    arm: Arm
    insertion: InsertionParameters
    options: PlanOptions
    pin_frame: str
    hole_frame: str
    start_hole: str
    pin_shape: PinShape
    hole_shape: HoleShape
    hand: HandSpec
    hand_al: str
    hand_error: Uncertainty | None
    park: pin.SE3
    q_park: Configuration
    d_i: float
    target_end: PinEnd
    pin_from_end: pin.SE3
    base_world: World
    gross: GrossMotionCheck
    counters: PlanCounters = field(default_factory=PlanCounters)
    from_park: bool = True

    @property
    def start_words(self) -> str:
        """Where the arm starts, for messages: ``BPARK``, or where the last step left it."""
        return self.park_al if self.from_park else "where the last step left the arm"

    @property
    def pin_al(self) -> str:
        """AL name of the pin (``PIN1``)."""
        return self.graph.al_names[self.pin_frame]

    @property
    def hole_al(self) -> str:
        """AL name of the target hole (``BH1``)."""
        return self.graph.al_names[self.hole_frame]

    @property
    def park_al(self) -> str:
        """AL name of the park frame (``BPARK``)."""
        assert self.spec.manipulator is not None  # build_context requires it
        return self.spec.manipulator.park.al_name

    @property
    def world_hole(self) -> pin.SE3:
        """Nominal pose of the target hole in the world."""
        return self.graph.world_from(self.hole_frame)

    @cached_property
    def hole_errors(self) -> ErrorReport:
        """The target hole's own errors in the world (``world⁻¹ ∘ hole``), no hand error.

        One computation for the task: the hole-tilt refusal reads its certified tilt, every
        candidate's seated hand its certified box.
        """
        chain = chain_between(self.graph, WORLD, self.hole_frame)
        return estimate_errors(chain, WORLD, self.hole_frame)

    @property
    def world_pin(self) -> pin.SE3:
        """Nominal initial pose of the pin in the world."""
        return self.graph.world_from(self.pin_frame)

    def nearest(self, world_from_hand: pin.SE3, q_from: Configuration) -> Configuration | None:
        """The configuration reaching a pose with the smallest largest joint change from ``q_from``.

        :func:`synth.models.arm.nearest_solution`, the rule the replay moves by: consecutive
        points of a move stay on one arm branch (counted as one IK call).
        """
        self.counters.ik += 1
        return nearest_solution(self.arm, self.arm.inverse(world_from_hand, hint=q_from), q_from)

    def motion(self, waypoints: list[Configuration]) -> float:
        """Duration [s] of a move through ``waypoints`` by the configured rule (one call)."""
        self.counters.motion_time += 1
        return motion_time(self.arm.limits, waypoints, self.options.timing_rule).duration

    def obstruction(
        self, scene: CollisionScene, waypoints: list[Configuration], motion: str
    ) -> str | None:
        """Why a gross motion through ``waypoints`` is not clear, or None (one sweep, counted)."""
        found = self.obstructed(scene, waypoints, motion)
        return None if found is None else found[0]

    def obstructed(
        self, scene: CollisionScene, waypoints: list[Configuration], motion: str
    ) -> tuple[str, SweepResult] | None:
        """:meth:`obstruction`'s reason with the sweep that found it (one sweep, counted)."""
        self.counters.sweeps += 1
        return self.gross.obstructed(scene, waypoints, motion)

    def bound(self, objective: NDArray[np.float64], space: ParameterSpace) -> Interval:
        """Extrema of ``objective · v`` over ``space`` (closed form or LP), counted."""
        self.counters.count_bounds(space)
        return bound_linear(objective, space)


def end_from_hand(ctx: PlanContext, grasp: Grasp) -> pin.SE3:
    """The hand in the frame of the inserted pin end: ``T_pin_end⁻¹ ∘ T_pin_hand``."""
    return ctx.pin_from_end.inverse() * grasp.pin_from_hand()


def hand_at(ctx: PlanContext, grasp: Grasp, hole_from_end: pin.SE3) -> pin.SE3:
    """World pose of the hand when the pin end is at ``hole_from_end`` (hole frame)."""
    return ctx.world_hole * hole_from_end * end_from_hand(ctx, grasp)


def _require(spec: TaskSpec) -> None:
    if spec.insertion is None:
        raise SpecError("insertion", "synth plan needs an 'insertion' section (pin and hole)")
    if spec.manipulator is None:
        raise SpecError("manipulator", "synth plan needs a 'manipulator' section (arm and park)")
    if spec.insertion.start_hole is None:
        raise SpecError(
            "insertion.start_hole",
            "synth plan needs the hole the pin starts in (the grasp is planned there, seed §4.3.1)",
        )


def start_depth(graph: AttributeGraph, start_hole: str, pin_frame: str) -> float:
    """d_i [m]: depth of the pin tip below the mouth of its start hole (seed L2036).

    The pin must stand in its start hole tip first, its axis along the hole's outward normal
    (seed L2036: "the origin of the pin's coordinate system is at the pin tip inserted into the
    hole"); then ``d_i = −z`` of the tip in the hole frame.
    """
    hole_from_pin = graph.relative(start_hole, pin_frame)
    axis = hole_from_pin.rotation[:, 2]
    if float(axis[2]) < math.cos(math.radians(1.0)):
        raise SpecError(
            f"frames.{pin_frame}",
            f"the pin must stand tip first in its start hole {start_hole!r} with its axis along "
            "the hole's normal (seed L2036)",
        )
    return -float(hole_from_pin.translation[2])


def pin_end_frame(pin_shape: PinShape, end: PinEnd) -> pin.SE3:
    """Frame of the pin end that enters the target hole, in the pin frame.

    ``tip``: the pin frame itself. ``head``: ``trans(rot(x̂, 180°), (0, 0, l))``, the far end
    with z pointing back along the pin, so that in both cases z leaves the hole.
    """
    if end == "tip":
        return pin.SE3.Identity()
    return pin.SE3(pin.exp3(np.array([math.pi, 0.0, 0.0])), np.array([0.0, 0.0, pin_shape.length]))


def plan_context(
    spec: TaskSpec,
    options: PlanOptions | None = None,
    base_dir: Path | str | None = None,
    start: Configuration | None = None,
) -> PlanContext:
    """Read the task into a :class:`PlanContext`; raise ``SpecError``/``UnreachableError``.

    ``start`` is where the arm begins (a later step of a sequence starts where the last one
    ended); default: its configuration at the park frame (:func:`park_configuration`).
    """
    with spec.lines_on_errors():
        _require(spec)
    graph = believed_graph(spec)  # objects located by contacts: derived pose and block
    spec = graph.spec
    assert spec.insertion is not None and spec.manipulator is not None
    opts = options or PlanOptions()
    insertion = derive(graph, spec.insertion)
    with spec.lines_on_errors():  # a step's fields stand at insertions.steps[i]
        refuse_unprovable(
            insertion,
            graph.al_names[insertion.pin],
            graph.al_names[insertion.hole],
            opts.reading_floor,
            spec.line_of,
        )
    assert insertion.start_hole is not None
    pin_shape = graph.nodes[insertion.pin].shape
    hole_shape = graph.nodes[insertion.hole].shape
    assert isinstance(pin_shape, PinShape) and isinstance(hole_shape, HoleShape)
    manip = spec.manipulator
    arm = task_arm(spec, base_dir)
    park = pose_to_se3(manip.park.pose)
    counters = PlanCounters()
    counters.ik += 1
    if start is None:
        with spec.lines_on_errors():
            q_park = park_configuration(
                arm,
                park,
                nominal_environment(graph, arm),
                manip.park.al_name,
                opening=hand_openings(pin_shape.diameter, opts)[0],
            )
    else:
        q_park = np.array(start, dtype=float)
    d_i = start_depth(graph, insertion.start_hole, insertion.pin)
    end: PinEnd = "tip" if insertion.direction == "parallel" else "head"
    pin_al = graph.al_names[insertion.pin]
    facts: list[Fact] = [
        Task(spec.name),
        InHole(pin_al, graph.al_names[insertion.start_hole], round(d_i, 9)),
        At(pin_al, graph.al_names[insertion.start_hole]),
        Holding(manip.al_name, "nothing"),
        HandError(manip.al_name, "manipulator.hand_error" if manip.hand_error else "exact"),
    ]
    for name, link in graph.links.items():
        if link.uncertainty is not None and link.uncertainty.bounds():
            facts.append(Uncertain(graph.al_names[name], f"frames.{name}.uncertainty"))
    return PlanContext(
        spec=spec,
        graph=graph,
        arm=arm,
        insertion=insertion,
        options=opts,
        pin_frame=insertion.pin,
        hole_frame=insertion.hole,
        start_hole=insertion.start_hole,
        pin_shape=pin_shape,
        hole_shape=hole_shape,
        hand=arm.hand,
        hand_al=manip.al_name,
        hand_error=manip.hand_error,
        park=park,
        q_park=q_park,
        d_i=d_i,
        target_end=end,
        pin_from_end=pin_end_frame(pin_shape, end),
        base_world=World.root(facts, label="task"),
        gross=GrossMotionCheck.of(arm, graph, insertion.pin, manip.hand_error, q_park),
        counters=counters,
        from_park=start is None,
    )
