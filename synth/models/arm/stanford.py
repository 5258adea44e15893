"""The Stanford (Scheinman) arm of the seed: model building and the closed-form inverse.

Kinematics (seed ch. III, L843–1000). The arm is θ1 (column, about base z), θ2 (shoulder, about
the joint-1 y axis, offset S2 along it), S3 (prismatic boom), then a spherical wrist θ4, θ5, θ6
(z–y–z) whose centre is the end of the boom; the hand frame is S6 further along z6. The seed's
two partial transforms (L993–1000) factor the hand pose as T = A1..3 · A4..6 with

    R03 = Rz(θ1)·Ry(θ2)·Rz(−90°),   p03 = Rz(θ1)·(0, S2, 0) + R03·(0, 0, S3) + (0, 0, S1),
    R36 = Rz(θ4)·Ry(θ5)·Rz(θ6),     p36 = R36·(0, 0, S6),

which multiplies out to the twelve forward equations (2)–(13). The Pinocchio model below uses
exactly these joints (RZ, RY, PZ, RZ, RY, RZ) and placements, with the base pose folded into
joint 1, so ``forwardKinematics`` reproduces (2)–(13) in world coordinates.

The inverse follows eqs. (14)–(32): subtract S6·a from the hand position to get the wrist centre
(14)–(16), solve θ1 (17)–(19), θ2 and S3 (20)–(21), then θ5, θ4, θ6 from the rotation
R36 = R03ᵀ·R (22)–(32). Of the eight algebraic solutions (two θ1 roots × two signs of S3 × two
wrist flips) at most two are attainable inside the joint limits (seed L895).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray
from pydantic import ValidationError

from synth.exceptions import ArmModelError, SpecError, SynthError
from synth.models.arm.arm import Arm
from synth.models.arm.bodies import Body, box_at, cylinder_along
from synth.models.arm.hand import hand_bodies, palm_top
from synth.models.arm.limits import JointKind, JointLimits
from synth.models.graph import pose_to_se3
from synth.models.manipulator import HandSpec
from synth.models.spec_fields import Pose
from synth.models.yamlread import read_yaml
from synth.units import parse_quantity, rate_si

STANFORD_PARAMETERS_PATH: Path = (
    Path(__file__).resolve().parents[3] / "fixtures" / "arms" / "stanford.yaml"
)
"""The shipped parameter file (``fixtures/arms/stanford.yaml``), every value with its source."""

JOINT_NAMES: tuple[str, ...] = ("theta1", "theta2", "S3", "theta4", "theta5", "theta6")
LINK_NAMES: tuple[str, ...] = (
    "column",
    "shoulder",
    "sleeve",
    "boom",
    "wrist_roll",
    "wrist_pitch",
    "wrist_body",
)
"""Link (frame) names; ``LINK_NAMES[k]`` is carried by joint k (0 = the fixed base)."""
HAND_FRAME = "hand"
THETA5 = 4
"""Index of θ5 in a configuration: the "elbow" the seed's grasp rating examines (L2086)."""

_RZ_MINUS_90 = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
_TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class StanfordParameters:
    """Link lengths [m], joint limits and collision envelopes of the Stanford arm.

    ``s1``: base to shoulder axis along the column; ``s2``: shoulder offset along the joint-2
    axis; ``s6``: wrist centre to hand frame along z6 (eqs. 2–13). ``default_base`` is the base
    pose in the world used when a task gives none (chosen for the seed's workcell, see the
    parameter file). ``geometry`` maps a link name to its envelope description; ``sources`` maps
    each value to where it came from.
    """

    s1: float
    s2: float
    s6: float
    limits: JointLimits
    default_base: Pose = field(default_factory=Pose)
    geometry: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    sources: Mapping[str, str] = field(default_factory=dict)

    @cached_property
    def bounds(self) -> tuple[tuple[float, float, bool], ...]:
        """(lower, upper, is_revolute) per joint as Python floats, for the scalar inverse."""
        lim = self.limits
        return tuple(
            (float(lo), float(hi), kind == "revolute")
            for lo, hi, kind in zip(lim.lower, lim.upper, lim.kinds, strict=True)
        )


def _quantity(entry: Any, dim: str, where: str) -> float:
    try:
        return parse_quantity(entry, dim)  # type: ignore[arg-type]
    except SynthError as exc:
        raise ArmModelError(exc.message, where) from None


def _rate(text: Any, kind: JointKind, order: int, where: str) -> float:
    """SI value of a joint rate (order 1: velocity, 2: acceleration, 3: jerk)."""
    try:
        return rate_si(text, order, kind)
    except SynthError as exc:
        raise ArmModelError(f"{kind} joint rate of order {order}: {exc.message}", where) from None


def load_stanford_parameters(path: Path | str | None = None) -> StanfordParameters:
    """Read a Stanford arm parameter file (default: ``fixtures/arms/stanford.yaml``)."""
    source = Path(path) if path is not None else STANFORD_PARAMETERS_PATH
    try:
        raw = read_yaml(source.read_text(encoding="utf-8"), source=str(source)).data
    except (OSError, UnicodeDecodeError) as exc:
        raise ArmModelError(
            f"cannot read the Stanford arm parameters: {exc}", str(source)
        ) from None
    except SpecError as exc:  # the task loader's limits and messages, with the slip's line
        line = f" (line {exc.line})" if exc.line is not None else ""
        raise ArmModelError(
            f"cannot read the Stanford arm parameters{line}: {exc.detail}", str(source)
        ) from None
    where = str(source)
    try:
        kin = raw["kinematics"]
        joints = raw["joints"]
    except (KeyError, TypeError):
        raise ArmModelError("needs 'kinematics' and 'joints' sections", where) from None
    if [j.get("name") for j in joints] != list(JOINT_NAMES):
        raise ArmModelError(f"joints must be {', '.join(JOINT_NAMES)} in that order", where)
    sources = {k: str(kin[k].get("source", "")) for k in ("S1", "S2", "S6")}
    kinds: list[JointKind] = []
    lower, upper, velocity, acceleration = [], [], [], []
    for j in joints:
        kind: JointKind = j["kind"]
        dim = "angle" if kind == "revolute" else "length"
        w = f"{where}: joint {j['name']}"
        kinds.append(kind)
        lower.append(_quantity(j["lower"], dim, w))
        upper.append(_quantity(j["upper"], dim, w))
        velocity.append(_rate(j["velocity"], kind, 1, w))
        acceleration.append(_rate(j["acceleration"], kind, 2, w))
        sources[j["name"]] = str(j.get("source", ""))
    limits = JointLimits(
        JOINT_NAMES,
        tuple(kinds),
        np.array(lower),
        np.array(upper),
        np.array(velocity),
        np.array(acceleration),
    )
    try:
        default_base = Pose.model_validate(raw.get("default_base", {}))
    except ValidationError as exc:
        raise ArmModelError(f"bad default_base: {exc.errors()[0]['msg']}", where) from None
    return StanfordParameters(
        default_base=default_base,
        s1=_quantity(kin["S1"]["value"], "length", where),
        s2=_quantity(kin["S2"]["value"], "length", where),
        s6=_quantity(kin["S6"]["value"], "length", where),
        limits=limits,
        geometry=dict(raw.get("geometry", {})),
        sources=sources,
    )


def build_stanford_model(
    params: StanfordParameters, world_from_base: pin.SE3 | None = None
) -> pin.Model:
    """Build the Pinocchio model of eqs. (2)–(13), base at T_world_base, with a ``hand`` frame.

    Joint placements (parent joint frame → joint frame): θ1 at T_wb·trans(0, 0, S1) about z;
    θ2 at trans(0, S2, 0) about y; S3 along z; θ4 at rot(z, −90°) about z (the seed's frame 3
    has x3 = −y of the θ2 frame, L995); θ5 about y; θ6 about z; hand = trans(0, 0, S6).
    """
    world_from_base = pin.SE3.Identity() if world_from_base is None else world_from_base
    lim = params.limits
    model = pin.Model()
    model.name = "stanford"
    joint_models = (
        pin.JointModelRZ(),
        pin.JointModelRY(),
        pin.JointModelPZ(),
        pin.JointModelRZ(),
        pin.JointModelRY(),
        pin.JointModelRZ(),
    )
    placements = (
        world_from_base * pin.SE3(np.eye(3), np.array([0.0, 0.0, params.s1])),
        pin.SE3(np.eye(3), np.array([0.0, params.s2, 0.0])),
        pin.SE3.Identity(),
        pin.SE3(_RZ_MINUS_90, np.zeros(3)),
        pin.SE3.Identity(),
        pin.SE3.Identity(),
    )
    model.addFrame(pin.Frame(LINK_NAMES[0], 0, 0, world_from_base, pin.FrameType.BODY))
    parent = 0
    for k, (jm, placement) in enumerate(zip(joint_models, placements, strict=True)):
        parent = model.addJoint(
            parent,
            jm,
            placement,
            JOINT_NAMES[k],
            np.array([1e3]),
            np.array([lim.velocity[k]]),
            np.array([lim.lower[k]]),
            np.array([lim.upper[k]]),
        )
        model.appendBodyToJoint(parent, pin.Inertia.Zero(), pin.SE3.Identity())
        model.addFrame(
            pin.Frame(LINK_NAMES[k + 1], parent, 0, pin.SE3.Identity(), pin.FrameType.BODY)
        )
    hand = pin.SE3(np.eye(3), np.array([0.0, 0.0, params.s6]))
    model.addFrame(pin.Frame(HAND_FRAME, parent, 0, hand, pin.FrameType.OP_FRAME))
    return model


def _shape(
    spec: Mapping[str, Any], hand: HandSpec, s6: float, where: str
) -> tuple[coal.CollisionGeometry, pin.SE3]:
    def length(key: str) -> float:
        value = spec[key]
        if value == "palm":
            # Up to the palm's rear face: S6 − (L_f + h_palm) from the wrist centre.
            return s6 - palm_top(hand)
        return _quantity(value, "length", f"{where}.{key}")

    kind = spec.get("shape")
    if kind == "cylinder":
        return cylinder_along(length("radius"), length("from"), length("to"), spec.get("axis", "z"))
    if kind == "box":
        size = tuple(_quantity(v, "length", f"{where}.size") for v in spec["size"])
        if "from" in spec:
            z0, z1 = length("from"), length("to")
            return box_at((size[0], size[1], z1 - z0), (0.0, 0.0, (z0 + z1) / 2))
        return box_at((size[0], size[1], size[2]), (0.0, 0.0, 0.0))
    if kind == "sphere":
        return coal.Sphere(length("radius")), pin.SE3.Identity()
    raise ArmModelError(f"unknown shape {kind!r} (cylinder, box or sphere)", where)


def stanford_link_bodies(params: StanfordParameters, hand: HandSpec) -> list[Body]:
    """Make the parameter file's link envelopes into bodies on joints 0–6 (no hand)."""
    bodies = []
    for joint, link in enumerate(LINK_NAMES):
        if link not in params.geometry:
            raise ArmModelError(f"no collision envelope for link {link!r}", "geometry")
        geometry, placement = _shape(params.geometry[link], hand, params.s6, f"geometry.{link}")
        bodies.append(Body(link, joint, link, placement, geometry, "arm"))
    return bodies


def _shifts(angle: float, lo: float, hi: float, tol: float) -> list[float]:
    """Every angle ≡ ``angle`` (mod 2π) inside [lo − tol, hi + tol], clipped into [lo, hi]."""
    if lo - tol <= angle <= hi + tol and hi - lo < _TWO_PI - 2 * tol:
        return [min(max(angle, lo), hi)]  # the common case: in range, no other representative
    k_min = math.ceil((lo - tol - angle) / _TWO_PI)
    k_max = math.floor((hi + tol - angle) / _TWO_PI)
    return [min(max(angle + k * _TWO_PI, lo), hi) for k in range(k_min, k_max + 1)]


def stanford_inverse_all(
    params: StanfordParameters,
    rotation: NDArray[np.float64],
    translation: NDArray[np.float64],
    theta4_degenerate: float = 0.0,
) -> list[tuple[float, float, float, float, float, float]]:
    """All algebraic solutions (θ1, θ2, S3, θ4, θ5, θ6) [rad, m] of T_base_hand, limits ignored.

    Wrist centre (14)–(16): (Tx, Ty, Tz) = p − S6·a. With ρ = s2·S3, (Tx, Ty) = Rz(θ1)·(ρ, S2), so
    ρ = ∓√(Tx² + Ty² − S2²) and θ1 = atan2(Ty, Tx) − atan2(S2, ρ): the same two roots as the
    tangent-half-angle form (17)–(19), without its special case (18) at S2 + Ty = 0. Then
    S3 = ±√(ρ² + (Tz − S1)²) and θ2 = atan2(ρ/S3, (Tz − S1)/S3) (20)–(21). The seed keeps the "−"
    root with S3 > 0 (θ2 < 0); the others are returned too and fail the joint limits.

    Wrist (22)–(32): R36 = R03ᵀ·R; c5 = R36[2,2] and s5 = ±√(R36[0,2]² + R36[1,2]²) (26);
    θ4 = atan2(R36[1,2]/s5, R36[0,2]/s5) (28). θ6 is read from the residual
    Ry(−θ5)·Rz(−θ4)·R36 = Rz(θ6), which equals (32) when s5 ≠ 0 and stays exact as s5 → 0; at
    s5 = 0 exactly (the degenerate case (27)) only θ4 + θ6 is defined and θ4 is set to
    ``theta4_degenerate``, so both wrist flips coincide and one is returned.
    """
    s1, s2, s6 = params.s1, params.s2, params.s6
    r = rotation
    ax, ay, az = float(r[0, 2]), float(r[1, 2]), float(r[2, 2])
    tx = float(translation[0]) - s6 * ax
    ty = float(translation[1]) - s6 * ay
    tz = float(translation[2]) - s6 * az
    rho_sq = tx * tx + ty * ty - s2 * s2
    if rho_sq < 0.0:
        if rho_sq < -1e-14 * max(1.0, s2 * s2):
            return []
        rho_sq = 0.0
    rho_abs = math.sqrt(rho_sq)
    h = tz - s1
    nx, ny, nz = float(r[0, 0]), float(r[1, 0]), float(r[2, 0])
    out: list[tuple[float, float, float, float, float, float]] = []
    for rho in (-rho_abs, rho_abs) if rho_abs > 0.0 else (0.0,):
        th1 = math.atan2(ty, tx) - math.atan2(s2, rho)
        th1 = math.atan2(math.sin(th1), math.cos(th1))
        c1, sn1 = math.cos(th1), math.sin(th1)
        extension = math.hypot(rho, h)
        if extension == 0.0:
            continue
        for s3 in (extension, -extension):
            th2 = math.atan2(rho / s3, h / s3)
            c2, sn2 = math.cos(th2), math.sin(th2)
            # Columns of R03 (L995): x3 = (s1, −c1, 0), y3 = (c1c2, s1c2, −s2),
            # z3 = (c1s2, s1s2, c2).
            x3 = (sn1, -c1, 0.0)
            y3 = (c1 * c2, sn1 * c2, -sn2)
            z3 = (c1 * sn2, sn1 * sn2, c2)
            r00 = x3[0] * nx + x3[1] * ny
            r10 = y3[0] * nx + y3[1] * ny + y3[2] * nz
            r20 = z3[0] * nx + z3[1] * ny + z3[2] * nz
            r02 = x3[0] * ax + x3[1] * ay  # (22): c4·s5
            r12 = y3[0] * ax + y3[1] * ay + y3[2] * az  # (24)/(25) combination: s4·s5
            r22 = z3[0] * ax + z3[1] * ay + z3[2] * az  # (26): c5
            s5_abs = math.hypot(r02, r12)
            if s5_abs == 0.0:
                # Degenerate (27): θ5 = 0 (or 180°), only θ4 + θ6 is fixed.
                th5 = 0.0 if r22 > 0 else math.pi
                th4 = theta4_degenerate
                c4, s4 = math.cos(th4), math.sin(th4)
                u0 = c4 * r00 + s4 * r10
                u1 = -s4 * r00 + c4 * r10
                c5, s5 = math.cos(th5), math.sin(th5)
                th6 = math.atan2(u1, c5 * u0 - s5 * r20)
                out.append((th1, th2, s3, th4, th5, th6))
                continue
            for sign in (1.0, -1.0):
                s5 = sign * s5_abs
                th5 = math.atan2(s5, r22)
                th4 = math.atan2(sign * r12, sign * r02)  # (28)
                c4, s4 = math.cos(th4), math.sin(th4)
                c5 = r22 / math.hypot(s5, r22)
                s5n = s5 / math.hypot(s5, r22)
                # First column of Ry(−θ5)·Rz(−θ4)·R36 = Rz(θ6): (c6, s6, 0).
                u0 = c4 * r00 + s4 * r10
                u1 = -s4 * r00 + c4 * r10
                th6 = math.atan2(u1, c5 * u0 - s5n * r20)
                out.append((th1, th2, s3, th4, th5, th6))
    return out


def stanford_inverse(
    params: StanfordParameters,
    rotation: NDArray[np.float64],
    translation: NDArray[np.float64],
    theta4_degenerate: float = 0.0,
    tolerance: float = 1e-10,
) -> list[NDArray[np.float64]]:
    """Every attainable solution of T_base_hand: eqs. (14)–(32) filtered by the joint limits.

    Revolute angles are shifted by multiples of 2π into their range (at most one shift fits
    the Stanford arm's ranges, all under 360°); values within ``tolerance`` [rad | m] of a limit
    are clipped onto it. Duplicates (within 1e-12) are dropped. Order: the seed's root first.
    """
    bounds = params.bounds
    accepted: list[list[float]] = []
    for cand in stanford_inverse_all(params, rotation, translation, theta4_degenerate):
        combos: list[list[float]] = [[]]
        for value, (lo, hi, revolute) in zip(cand, bounds, strict=True):
            if revolute:
                values = _shifts(value, lo, hi, tolerance)
            elif lo - tolerance <= value <= hi + tolerance:
                values = [min(max(value, lo), hi)]
            else:
                values = []
            if not values:
                combos = []
                break
            combos = (
                [[*c, v] for c in combos for v in values]
                if len(values) > 1
                else [c + values for c in combos]
            )
        for q in combos:
            if all(max(abs(a - b) for a, b in zip(q, s, strict=True)) >= 1e-12 for s in accepted):
                accepted.append(q)
    return [np.array(q) for q in accepted]


@dataclass(frozen=True, eq=False)
class StanfordInverse:
    """The closed form as an arm's inverse: T_world_hand ↦ every attainable configuration.

    T_base_T6 = T_world_base⁻¹ · T_world_hand · tool_offset⁻¹, then :func:`stanford_inverse`.
    """

    params: StanfordParameters
    world_from_base: pin.SE3
    tool_offset: pin.SE3 = field(default_factory=pin.SE3.Identity)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_base_inv", self.world_from_base.inverse())
        object.__setattr__(self, "_tool_inv", self.tool_offset.inverse())

    def __call__(
        self, world_from_hand: pin.SE3, hint: ArrayLike | None = None
    ) -> list[NDArray[np.float64]]:
        """Every attainable solution (seed eqs. 14–32 and the joint limits).

        ``hint`` is unused: no Stanford joint turns through more than 2π (L963), so a solution
        has no whole-turn aliases to choose among.
        """
        t = self._base_inv * world_from_hand * self._tool_inv  # type: ignore[attr-defined]
        return stanford_inverse(self.params, t.rotation, t.translation)


def build_stanford_arm(
    hand: HandSpec,
    world_from_base: pin.SE3 | None = None,
    params: StanfordParameters | None = None,
    tool_offset: pin.SE3 | None = None,
) -> Arm:
    """Build the Stanford arm: model, closed-form inverse, link and hand bodies.

    ``world_from_base`` defaults to the parameter file's ``default_base`` (the placement
    chosen for the seed's workcell); ``tool_offset`` moves AL's hand frame off Paul's T6.
    """
    p = params if params is not None else load_stanford_parameters()
    world_from_base = pose_to_se3(p.default_base) if world_from_base is None else world_from_base
    offset = pin.SE3.Identity() if tool_offset is None else tool_offset
    model = build_stanford_model(p, world_from_base)
    t6 = model.frames[model.getFrameId(HAND_FRAME)]
    if not np.allclose(offset.homogeneous, np.eye(4)):
        t6.placement = t6.placement * offset
    joint6 = int(t6.parentJoint)
    bodies = stanford_link_bodies(p, hand)
    bodies[0] = Body(
        bodies[0].name,
        0,
        bodies[0].link,
        world_from_base * bodies[0].placement,
        bodies[0].geometry,
        "arm",
    )
    bodies += hand_bodies(hand, joint6, HAND_FRAME, t6.placement, hand.max_opening)
    return Arm(
        name="stanford",
        model=model,
        hand_frame=model.getFrameId(HAND_FRAME),
        limits=p.limits,
        hand=hand,
        bodies=tuple(bodies),
        world_from_base=world_from_base,
        closed_form=StanfordInverse(p, world_from_base, offset),
        grasp_joint=THETA5,
    )
