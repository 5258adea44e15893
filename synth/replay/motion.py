"""One motion of the replay's arm: its segments, how the held pin moves along them, its timeline.

A ``MOVE`` becomes straight joint-space :class:`Segment` s between the inverse-kinematics
solutions of its targets, each with the hand positioning errors at its ends and a quintic time
law (seed L3846: AL's 5th-order polynomials). Along a segment the held pin flies free, is guided
by a hole, or slides along a surface (:class:`Phase`). A :class:`Motion` is the timeline the
machine plays back: the shared timeline of :mod:`synth.al.timeline` (instants where monitors
are checked, resume and stop), the state at any instant (:class:`MotionState`), and how it ends
early (:class:`Stop`). Units: [m], [rad], [s], [N].
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal, Protocol

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.al.timeline import Timeline
from synth.models.arm import Obstacle
from synth.models.workcell import HoleSite
from synth.replay.report import Violation
from synth.vec3 import norm3

PoseAt = Callable[[float], pin.SE3]
"""s ∈ [0, 1] ↦ the pin's true world pose [m]."""

__all__ = [
    "Motion",
    "MotionObserver",
    "MotionState",
    "Phase",
    "Segment",
    "Slide",
    "Stop",
    "point_on",
    "push_reaction",
    "quintic",
    "quintic_inverse",
]


_EYE = np.eye(3)
_EYE.flags.writeable = False


def quintic(tau: float) -> float:
    """s(τ) = 10τ³ − 15τ⁴ + 6τ⁵, the rest-to-rest quintic time law."""
    tau = min(max(tau, 0.0), 1.0)
    return tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau))


def quintic_inverse(s: float) -> float:
    """τ with s(τ) = s (bisection; s is increasing on [0, 1]); exactly 0 and 1 at the ends.

    The law is flat at both ends (s'(0) = s'(1) = 0): within ~2·10⁻⁶ of τ = 1 it rounds to
    1.0, so a bisection for s = 1 would stop that far short of the segment's end time.
    """
    if s <= 0.0:
        return 0.0
    if s >= 1.0:
        return 1.0
    lo, hi = 0.0, 1.0
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        if quintic(mid) < s:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


_SHORT_OF_PLANE = 1e-4
"""[m] how far short of the tangent plane's yield :meth:`Slide.deflection` tests the pin for
still touching. Along a face it does (it would be 0.1 mm into the face), and so does a pin
whose touching point has moved on a little (a pin slightly turned against a wall): the plane's
yield is kept, within 0.1 mm of the least, with one collision test. Past an edge the plane's
runs millimetres ahead and the least is found by bisection."""

_PLANE_TRUSTED = 2e-3
"""[m] a yield the tangent plane gives up to this is taken as it is, with no collision test: at
most a fifth of the arm's compliance too much past an edge, where the plane runs ahead (the
seed's search listing slides by 0.1–3 mm; testing each step made its trials 1.4× slower)."""

_YIELD_BISECTIONS = 16
"""Halvings of the yield past an edge: ≤ 1 cm / 2¹⁶ < 0.2 µm."""


@dataclass(frozen=True, eq=False)
class Slide:
    """A pin sliding along ``obstacle``.

    ``normal``: the surface normal (world, towards the pin) where it touched; ``pin_point``: the
    pin's contact point (pin frame) [m]; ``origin``: where that point was when the slide began
    (world) [m]; ``pin_geometry``: the pin's solid (pin frame), for the yield past an edge.
    """

    obstacle: Obstacle
    normal: NDArray[np.float64]
    pin_point: NDArray[np.float64]
    origin: NDArray[np.float64]
    pin_geometry: coal.CollisionGeometry

    def deflection(self, pin_pose: pin.SE3) -> float:
        """How far [m] the arm yields along the normal n: the least δ ≥ 0 that keeps the pin out.

        Along a face the contact point stays on the plane it touched, δ = max(0, −n·(P x − x₀)),
        and a pin shifted by less is still in the face (tested 0.1 mm short of it). Where it
        touched an edge, that tangent plane is not the obstacle's surface: a pin lowered past a
        box's top edge would be pushed ever farther out by it and stall in the air beside the
        box. There δ is the least shift along n that leaves the pin clear of the obstacle (at
        most the plane's), by bisection on Coal's collision test, once the plane's exceeds
        :data:`_PLANE_TRUSTED`.
        """
        plane = max(0.0, -float(self.normal @ (pin_pose.act(self.pin_point) - self.origin)))
        if plane <= _PLANE_TRUSTED or self._touches(pin_pose, plane - _SHORT_OF_PLANE):
            return plane
        if not self._touches(pin_pose, 0.0):
            return 0.0
        touching, clear = 0.0, plane - _SHORT_OF_PLANE
        for _ in range(_YIELD_BISECTIONS):
            middle = 0.5 * (touching + clear)
            if self._touches(pin_pose, middle):
                touching = middle
            else:
                clear = middle
        return clear

    def yielded(self, pin_pose: pin.SE3, deflection: float | None = None) -> pin.SE3:
        """The commanded pin pose moved by the arm's yield along the normal.

        ``deflection`` [m] is the yield when already known, else :meth:`deflection`'s.
        """
        shift = self.deflection(pin_pose) if deflection is None else deflection
        return pin.SE3(pin_pose.rotation, pin_pose.translation + shift * self.normal)

    def _touches(self, pin_pose: pin.SE3, shift: float) -> bool:
        """Whether the pin, moved by ``shift`` [m] along the normal, overlaps the obstacle."""
        moved = coal.Transform3s(pin_pose.rotation, pin_pose.translation + shift * self.normal)
        placed = self.obstacle.pose
        request, result = coal.CollisionRequest(), coal.CollisionResult()
        return bool(
            coal.collide(
                self.pin_geometry,
                moved,
                self.obstacle.geometry,
                coal.Transform3s(placed.rotation, placed.translation),
                request,
                result,
            )
        )


@dataclass(frozen=True, eq=False)
class Phase:
    """How the held pin moves from path parameter ``start`` on.

    Free, guided by ``hole``, or sliding (``slide``).
    """

    start: float
    hole: HoleSite | None = None
    slide: Slide | None = None


@dataclass(eq=False)
class Segment:
    """One straight joint-space segment q0 → q1, its hand errors and its timing."""

    q0: NDArray[np.float64]
    q1: NDArray[np.float64]
    e0: pin.SE3
    e1: pin.SE3
    t0: float
    duration: float
    phases: list[Phase] = field(default_factory=list)

    def q(self, s: float) -> NDArray[np.float64]:
        """The configuration at ``s`` ∈ [0, 1]: q0 + s·(q1 − q0) [rad | m]."""
        return self.q0 + s * (self.q1 - self.q0)

    def __post_init__(self) -> None:
        turn = pin.log3(self.e0.rotation.T @ self.e1.rotation)
        self._angle = norm3(turn)
        self._axis = turn / self._angle if self._angle > 0.0 else np.zeros(3)
        self._skew = pin.skew(self._axis)
        self._skew2 = self._skew @ self._skew
        self._r0 = np.array(self.e0.rotation)
        self._t0 = np.array(self.e0.translation)
        self._shift = np.array(self.e1.translation) - self._t0

    def error_rt(self, s: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(R, t) of the hand error at ``s``: R₀·exp(s·log(R₀ᵀR₁)), t₀ + s·(t₁ − t₀).

        The same path as :func:`synth.al.machine.interpolate`, with Rodrigues' formula.
        """
        if self._angle == 0.0:
            return self._r0, self._t0 + s * self._shift
        a = s * self._angle
        turn = _EYE + math.sin(a) * self._skew + (1.0 - math.cos(a)) * self._skew2
        return self._r0 @ turn, self._t0 + s * self._shift

    def error(self, s: float) -> pin.SE3:
        """The hand error at ``s`` as an SE3."""
        rotation, translation = self.error_rt(s)
        return pin.SE3(rotation, translation)

    def time(self, s: float) -> float:
        """Time [s] since the motion started at which the segment reaches ``s``."""
        return self.t0 + (self.duration * quintic_inverse(s) if self.duration > 0 else 0.0)

    def s_at(self, t: float) -> float:
        """The path parameter ``t`` [s] after the motion started (the quintic time law)."""
        if self.duration <= 0:
            return 1.0
        return quintic((t - self.t0) / self.duration)

    def phase_at(self, s: float) -> Phase:
        """How the held pin moves at ``s``: the last phase starting at or before it."""
        phase = self.phases[0] if self.phases else Phase(0.0)
        for candidate in self.phases:
            if candidate.start <= s:
                phase = candidate
        return phase


@dataclass(frozen=True, eq=False)
class MotionState:
    """The machine state at one instant of a motion."""

    q: NDArray[np.float64] | None
    hint: NDArray[np.float64]
    sensed: pin.SE3
    error: pin.SE3
    pin_pose: pin.SE3 | None
    hole: HoleSite | None
    depth: float
    opening: float


def _no_state(elapsed: float) -> MotionState:
    raise RuntimeError("a motion without states")


@dataclass(eq=False)
class Motion(Timeline):
    """A motion being played back.

    Its timeline (:class:`~synth.al.timeline.Timeline`: checkpoints, monitors, the contact
    force), the state at any instant ``state_at(elapsed)``, how it ends early (``stop``) and
    what runs when it ends normally (``finish``: a grasp, a release).
    """

    state_at: Callable[[float], MotionState] = _no_state
    stop: Stop | None = None
    finish: Callable[[], None] | None = None


class MotionObserver(Protocol):
    """Told how far each motion has been played: the hook of :mod:`synth.replay.trace`."""

    def played(self, motion: Motion, elapsed: float, paused: bool) -> None:
        """``motion`` has been played up to ``elapsed`` [s] after its start.

        ``paused``: a monitor fired and the motion may resume; otherwise it has ended there.
        Called before the machine takes on the state at ``elapsed``; ``motion.state_at`` gives
        every instant up to there.
        """


@dataclass(frozen=True, eq=False)
class Stop:
    """Where a motion ends early: at ``s`` of its last segment, by a contact or a violation.

    ``body`` touched ``obstacle`` at ``point`` [m]; ``reaction`` is the unit direction of the
    force on the hand (opposite to the motion of the touching point: a blocked arm pushes
    along its path).
    """

    s: float
    kind: Literal["seat", "surface", "violation"]
    body: str
    obstacle: str
    point: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    reaction: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    violation: Violation | None = None
    note: str = ""


def point_on(
    pose_at: Callable[[float], pin.SE3], point: NDArray[np.float64], s: float
) -> NDArray[np.float64]:
    """World position at ``s`` of ``point`` fixed in the moving frame ``pose_at``."""
    return np.asarray(pose_at(s).act(point), dtype=float)


def push_reaction(
    position: Callable[[float], NDArray[np.float64]], s: float
) -> NDArray[np.float64]:
    """−(direction of motion) of a point at ``s`` (finite difference); +ẑ if it is at rest."""
    step = 1e-4
    a, b = (s - step, s) if s >= step else (s, s + step)
    velocity = np.asarray(position(b), dtype=float) - np.asarray(position(a), dtype=float)
    norm = norm3(velocity)
    if norm < 1e-12:
        return np.array([0.0, 0.0, 1.0])
    return -velocity / norm
