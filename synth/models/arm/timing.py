"""Motion time: AL's quintic at the joint limits, ruckig's time-optimal profile, the seed's rule.

:func:`motion_time` is the one function the planner (ranking strategies by expected time) and
the replay (timing what it executes) both call, so the two never disagree.

**Quintic rule** (the default). The replay plays each segment of a move as AL's runtime does,
straight in joint space with the rest-to-rest quintic s(τ) = 10τ³ − 15τ⁴ + 6τ⁵ (seed L3846),
whose peaks over τ ∈ [0, 1] are |s′| = 15/8 (τ = ½), |s″| = 10/√3 (τ = ½ ∓ √3/6) and
|s‴| = 60 (τ = 0, 1). A segment Δq played over T keeps joint j within its limits iff
T ≥ (15/8)·|Δq_j|/v_j, T ≥ √((10/√3)·|Δq_j|/a_j) and T ≥ ∛(60·|Δq_j|/J_j): its duration is
the largest of these over the joints. (Playing the ruckig rule's durations with the quintic,
as the replay once did, drove the seed's first move to 1.34 × a joint's speed limit and 2.6 ×
an acceleration limit, in the simulation and the exported trajectory alike.)

**Ruckig rule.** A move q_0 → q_1 → … → q_m is planned segment by segment with ruckig under the
per-joint velocity, acceleration and (when given) jerk limits; each segment is time-optimal for
its boundary states, phase-synchronised so that a rest-to-rest segment follows the straight
joint-space line (what :func:`synth.models.arm.sweep.swept_segment` checks). At each via point
the arm keeps moving with velocity α_i·c_i, where c_ij = sgn·min(v_j, √(a_j·min(|Δ_-|, |Δ_+|)))
for a joint whose two adjacent displacements Δ_-, Δ_+ have the same sign and 0 otherwise, and
α_i ∈ [0, 1] is chosen by golden-section search on the two adjacent segment durations
(coordinate descent over the vias). α = 0 (stop at the via) is always a candidate, so blending
never makes a move slower. The multi-waypoint calculation of ruckig itself (Ruckig Pro / cloud)
is never used. Via accelerations are zero.

**Seed rule** (seed ch. V, L3846): per segment and joint, time = |Δq_j| ÷ v̄_j with v̄ the
highest average speed; the segment takes the slowest joint; the move adds a grace of 20 jiffies
(1 jiffy = 1/60 s). By default v̄ = (8/15)·v_max, the average speed of an AL quintic move whose
peak speed is v_max (:data:`~synth.models.arm.limits.QUINTIC_PEAK_TO_AVERAGE`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from ruckig import InputParameter, Result, Ruckig, RuckigError, Synchronization, Trajectory

from synth.exceptions import TrajectoryError
from synth.models.arm.limits import QUINTIC_PEAK_TO_AVERAGE, JointLimits

JIFFY: float = 1.0 / 60.0
"""[s] One jiffy, the AL/WAVE servo tick (seed L3846: 60 jiffies = 1 s)."""
SEED_GRACE: float = 20 * JIFFY
"""[s] Grace period added to every move by the seed's rule (20 jiffies, L3846)."""

Rule = Literal["quintic", "ruckig", "seed"]
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


@dataclass(frozen=True)
class TimingOptions:
    """Options of the ruckig rule."""

    blend_vias: bool = True
    """Pass through via points without stopping (AL's ``via``); False stops at every via."""
    search_steps: int = 12
    """Golden-section steps per via and sweep (each costs two segment calculations)."""
    sweeps: int = 2
    """Coordinate-descent passes over the vias."""


@dataclass(frozen=True)
class MotionTime:
    """A move's duration [s], per-segment durations [s] and the rule that produced them."""

    duration: float
    segments: tuple[float, ...]
    rule: Rule


@dataclass(frozen=True, eq=False)
class JointTrajectory:
    """A planned move: ruckig segments end to end, with the via velocities chosen."""

    segments: tuple[Trajectory, ...]
    via_velocities: tuple[NDArray[np.float64], ...]
    start: NDArray[np.float64]

    @property
    def durations(self) -> tuple[float, ...]:
        """Segment durations [s]."""
        return tuple(float(s.duration) for s in self.segments)

    @property
    def duration(self) -> float:
        """Total duration [s]."""
        return float(sum(self.durations))

    def at_time(
        self, t: float
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Position, velocity, acceleration at time ``t`` [s] (clamped to [0, duration])."""
        if not self.segments:
            zero = np.zeros_like(self.start)
            return self.start.copy(), zero, zero.copy()
        t = min(max(t, 0.0), self.duration)
        for segment in self.segments:
            if t <= segment.duration or segment is self.segments[-1]:
                p, v, a = segment.at_time(min(t, segment.duration))
                return np.array(p), np.array(v), np.array(a)
            t -= segment.duration
        raise AssertionError("unreachable")

    def position(self, t: float) -> NDArray[np.float64]:
        """Position at time ``t`` [s]."""
        return self.at_time(t)[0]

    def sample(self, dt: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Sample every ``dt`` [s] (and the end): times and positions, shape (k, n)."""
        times = np.append(np.arange(0.0, self.duration, dt), self.duration)
        return times, np.array([self.position(t) for t in times])


def _waypoints(limits: JointLimits, waypoints: Sequence[ArrayLike]) -> list[NDArray[np.float64]]:
    points = [np.asarray(w, dtype=float) for w in waypoints]
    if not points:
        raise TrajectoryError("a move needs at least one configuration")
    for i, p in enumerate(points):
        if p.shape != (limits.n,):
            raise TrajectoryError(
                f"waypoint {i} has {p.shape[0] if p.ndim else 0} joints, expected {limits.n}"
            )
        if not limits.contains(p, 1e-9):
            raise TrajectoryError(f"waypoint {i} is outside the joint limits")
    return points


class _Segments:
    """Ruckig calculations for one arm's limits, reusing the solver and input objects."""

    def __init__(self, limits: JointLimits) -> None:
        n = limits.n
        self.n = n
        self.otg = Ruckig(n)
        self.inp = InputParameter(n)
        self.inp.max_velocity = limits.velocity.tolist()
        self.inp.max_acceleration = limits.acceleration.tolist()
        self.inp.max_jerk = [math.inf] * n if limits.jerk is None else limits.jerk.tolist()
        self.inp.min_position = (limits.lower - 1e-6).tolist()  # waypoints may sit on a limit
        self.inp.max_position = (limits.upper + 1e-6).tolist()
        self.inp.synchronization = Synchronization.Phase
        self.zero = [0.0] * n
        self.scratch = Trajectory(n)  # the search's durations are calculated into it

    def plan(
        self,
        q0: NDArray[np.float64],
        v0: NDArray[np.float64],
        q1: NDArray[np.float64],
        v1: NDArray[np.float64],
        into: Trajectory | None = None,
    ) -> Trajectory | None:
        """Ruckig's trajectory from (q0, v0) to (q1, v1) at rest in acceleration, or None.

        ``into``: a trajectory to calculate into (ruckig overwrites it whole), for a search
        that reads only its duration; a new one otherwise.
        """
        inp = self.inp
        inp.current_position = q0.tolist()
        inp.current_velocity = v0.tolist()
        inp.current_acceleration = self.zero
        inp.target_position = q1.tolist()
        inp.target_velocity = v1.tolist()
        inp.target_acceleration = self.zero
        trajectory = Trajectory(self.n) if into is None else into
        try:
            result = self.otg.calculate(inp, trajectory)
        except (RuntimeError, RuckigError, ValueError):
            # RuckigError for limits it cannot time; ValueError for an error code its Python
            # enum lacks (-101 at a speed limit of 1e-6)
            return None
        return trajectory if result in (Result.Working, Result.Finished) else None

    def duration(
        self,
        q0: NDArray[np.float64],
        v0: NDArray[np.float64],
        q1: NDArray[np.float64],
        v1: NDArray[np.float64],
    ) -> float:
        trajectory = self.plan(q0, v0, q1, v1, self.scratch)
        return math.inf if trajectory is None else float(trajectory.duration)


def _via_caps(limits: JointLimits, points: list[NDArray[np.float64]]) -> list[NDArray[np.float64]]:
    caps = []
    for i in range(1, len(points) - 1):
        before, after = points[i] - points[i - 1], points[i + 1] - points[i]
        same = before * after > 0
        reach = np.sqrt(limits.acceleration * np.minimum(np.abs(before), np.abs(after)))
        caps.append(np.where(same, np.sign(after) * np.minimum(limits.velocity, reach), 0.0))
    return caps


def plan_trajectory(
    limits: JointLimits, waypoints: Sequence[ArrayLike], options: TimingOptions | None = None
) -> JointTrajectory:
    """Plan the ruckig-rule trajectory through ``waypoints``, at rest at both ends."""
    opts = options or TimingOptions()
    points = _waypoints(limits, waypoints)
    if len(points) == 1:
        return JointTrajectory((), (), points[0])
    seg = _Segments(limits)
    caps = _via_caps(limits, points) if opts.blend_vias else []
    alphas = [0.0] * len(caps)
    zero = np.zeros(limits.n)

    def velocity(i: int) -> NDArray[np.float64]:  # velocity at point i
        return zero if i == 0 or i == len(points) - 1 or not caps else alphas[i - 1] * caps[i - 1]

    def local(i: int, alpha: float) -> float:  # duration of the two segments around via i
        v = alpha * caps[i - 1]
        return seg.duration(points[i - 1], velocity(i - 1), points[i], v) + seg.duration(
            points[i], v, points[i + 1], velocity(i + 1)
        )

    for _ in range(opts.sweeps if caps else 0):
        for i in range(1, len(points) - 1):
            if not np.any(caps[i - 1]):
                continue
            lo, hi = 0.0, 1.0
            x1, x2 = hi - _GOLDEN * (hi - lo), lo + _GOLDEN * (hi - lo)
            f1, f2 = local(i, x1), local(i, x2)
            for _step in range(opts.search_steps):
                if f1 <= f2:
                    hi, x2, f2 = x2, x1, f1
                    x1 = hi - _GOLDEN * (hi - lo)
                    f1 = local(i, x1)
                else:
                    lo, x1, f1 = x1, x2, f2
                    x2 = lo + _GOLDEN * (hi - lo)
                    f2 = local(i, x2)
            candidates = {
                alphas[i - 1]: local(i, alphas[i - 1]),
                0.0: local(i, 0.0),
                1.0: local(i, 1.0),
                x1: f1,
                x2: f2,
            }
            alphas[i - 1] = min(candidates, key=lambda a: (candidates[a], a))

    segments = []
    for i in range(len(points) - 1):
        trajectory = seg.plan(points[i], velocity(i), points[i + 1], velocity(i + 1))
        if trajectory is None:
            raise TrajectoryError(f"ruckig found no trajectory for segment {i}")
        segments.append(trajectory)
    vias = tuple(velocity(i).copy() for i in range(1, len(points) - 1))
    return JointTrajectory(tuple(segments), vias, points[0])


def seed_motion_time(
    limits: JointLimits,
    waypoints: Sequence[ArrayLike],
    average_speed: ArrayLike | None = None,
    grace: float = SEED_GRACE,
) -> MotionTime:
    """Apply the seed's rule (L3846): Σ_segments max_j |Δq_j| / v̄_j, plus ``grace`` [s]."""
    points = _waypoints(limits, waypoints)
    v_bar = (
        limits.seed_average_speed()
        if average_speed is None
        else np.asarray(average_speed, dtype=float)
    )
    segments = tuple(float(np.max(np.abs(b - a) / v_bar)) for a, b in itertools.pairwise(points))
    return MotionTime(sum(segments) + grace, segments, "seed")


QUINTIC_PEAK_ACCELERATION: float = 10.0 / math.sqrt(3.0)
"""max |s″(τ)| of the quintic time law, at τ = ½ ∓ √3/6 (module docstring)."""
QUINTIC_PEAK_JERK: float = 60.0
"""max |s‴(τ)| of the quintic time law, at τ = 0 and 1."""


def quintic_motion_time(limits: JointLimits, waypoints: Sequence[ArrayLike]) -> MotionTime:
    """The quintic rule (module docstring): each segment the shortest quintic within limits."""
    points = _waypoints(limits, waypoints)
    segments = []
    for a, b in itertools.pairwise(points):
        distance = np.abs(b - a)
        bounds = [
            QUINTIC_PEAK_TO_AVERAGE * distance / limits.velocity,
            np.sqrt(QUINTIC_PEAK_ACCELERATION * distance / limits.acceleration),
        ]
        if limits.jerk is not None:
            bounds.append(np.cbrt(QUINTIC_PEAK_JERK * distance / limits.jerk))
        segments.append(float(np.max(bounds)))
    return MotionTime(sum(segments), tuple(segments), "quintic")


def motion_time(
    limits: JointLimits,
    waypoints: Sequence[ArrayLike],
    rule: Rule = "quintic",
    options: TimingOptions | None = None,
) -> MotionTime:
    """Duration [s] of a move from rest through ``waypoints`` to rest, by ``rule``.

    The planner ranks strategies by this and the replay plays it: both must call this
    function. ``waypoints`` are configurations [rad | m]: start, vias, goal. Only the quintic
    rule is what the replay (and an AL runtime) plays; ``ruckig`` (a time-optimal controller
    blending its vias) and ``seed`` (L3846) are kept for comparison.
    """
    if rule == "quintic":
        return quintic_motion_time(limits, waypoints)
    if rule == "seed":
        return seed_motion_time(limits, waypoints)
    if rule != "ruckig":
        raise ValueError(f"unknown timing rule {rule!r}: 'quintic', 'ruckig' or 'seed'")
    trajectory = plan_trajectory(limits, waypoints, options)
    return MotionTime(trajectory.duration, trajectory.durations, "ruckig")
