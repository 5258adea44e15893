"""The task specification: a pydantic schema for ``task.yaml``, SI units inside.

A task describes a pin-in-hole workcell (seed ch. IV, L1120–3290):

* ``frames`` — a tree of named objects and features. Every link has a parent (another frame or
  ``world``), a nominal pose relative to it, a kind (``rigid`` / ``nonrigid`` / ``independent``,
  as POINTY defines affixments, seed L6330 and L6840–6850) and an optional uncertainty block.
* ``insertion`` — which pin goes into which hole, with the parameters of seed §4.2
  (L1990–2010): direction, d_f, d_s, Δr_ok, Δθ_ok, derived from geometry unless overridden.
* ``manipulator`` — the arm model, its park frame and the hand's positioning errors.

Every dimensioned number carries its unit (``"3.85 cm"``, ``"5 deg"``), parsed by
:mod:`synth.units`; the validated model holds SI floats (m, rad, N). ``docs/task-spec.md`` is the
annotated reference. Semantic checks that need the whole tree (unknown parents, cycles, name
clashes, infeasible constraints) live in :mod:`synth.models.loader`, which can point at YAML
lines.
"""

from __future__ import annotations

import math
import re
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    PrivateAttr,
    field_validator,
    model_validator,
)

from synth.al.names import NameRole, al_name_problem
from synth.models.catalog import ARM_MODELS
from synth.models.contacts import ContactSpec
from synth.models.yamlread import PathKey, line_of, parse_path
from synth.units import (
    INCH,
    parse_quantity,
    rate_kind,
    rate_si,
    read_quantity,
    registry,
    si_magnitude,
)

_FRAME_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_-]*", re.ASCII)
"""A frame's own name (not its AL name): matched in full, so no trailing newline gets through."""

WORLD = "world"
"""Name of the root frame (the work station / table frame)."""

TRANSLATION_PARAMS: tuple[str, ...] = ("x", "y", "z")
ROTATION_PARAMS: tuple[str, ...] = ("rx", "ry", "rz")
PARAMS: tuple[str, ...] = TRANSLATION_PARAMS + ROTATION_PARAMS
"""Error parameters of a link, in the link's own frame: Δ = transl(x, y, z) ∘ rot(x̂, rx) ∘
rot(ŷ, ry) ∘ rot(ẑ, rz), applied on the right of the nominal pose (seed A.2, L3190–3200)."""


def _length(v: Any) -> float:
    return parse_quantity(v, "length")


def _angle(v: Any) -> float:
    return parse_quantity(v, "angle")


def _force(v: Any) -> float:
    return parse_quantity(v, "force")


Length = Annotated[float, BeforeValidator(_length)]
"""A length given with its unit, stored in [m]."""
Angle = Annotated[float, BeforeValidator(_angle)]
"""An angle given with its unit, stored in [rad]."""
Force = Annotated[float, BeforeValidator(_force)]
"""A force (or a weight such as ``8 oz``), stored in [N]."""
PositiveLength = Annotated[float, BeforeValidator(_length), Field(gt=0)]
NonNegativeLength = Annotated[float, BeforeValidator(_length), Field(ge=0)]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


def _check_al_name(value: str, *, role: NameRole = "frame") -> str:
    """``value`` upper-cased if it may name a ``role`` in AL (:func:`al_name_problem`)."""
    problem = al_name_problem(value, role=role)
    if problem:
        raise ValueError(problem)
    return value.upper()


class Rotation(_Model):
    """One elementary rotation ``rot(axis, angle)``; a pose composes a list left to right."""

    axis: Literal["x", "y", "z"]
    angle: Angle

    @model_validator(mode="before")
    @classmethod
    def _from_short_form(cls, data: Any) -> Any:
        # {z: "90 deg"} is the short form of {axis: z, angle: "90 deg"}.
        if isinstance(data, dict) and len(data) == 1:
            ((key, value),) = data.items()
            if key in ("x", "y", "z"):
                return {"axis": key, "angle": value}
        return data


class Pose(_Model):
    """Nominal pose of a frame in its parent: ``trans(rot_1 ∘ rot_2 ∘ …, translation)``."""

    translation: tuple[Length, Length, Length] = (0.0, 0.0, 0.0)
    rotation: tuple[Rotation, ...] = ()


class Bound(_Model):
    """Closed interval [lo, hi] of one error parameter, SI units; lo ≤ 0 ≤ hi."""

    lo: float
    hi: float


def _check_rotation_error(given: Any, largest_rad: float) -> None:
    """Refuse a rotation error of 90° or more: no error chain through it can be certified.

    The certified bound needs tr(ΔR − I) > −2 (:func:`synth.errors.estimate.estimate_errors`);
    one rotation by θ alone has tr(ΔR − I) = 2(cos θ − 1), which reaches −2 at θ = 90°.
    """
    if largest_rad >= math.pi / 2:
        raise ValueError(
            f"rotation error {given!r} reaches 90°: the error model certifies rotations below "
            "90° (a part known only that loosely has to be located before it is planned for)"
        )


def _bound(kind: Literal["length", "angle"]) -> Any:
    def parse(v: Any) -> Any:
        if isinstance(v, Bound | dict):
            return v
        if isinstance(v, list | tuple):
            if len(v) != 2:
                raise ValueError("a bound is one tolerance ('0.3 in' means ±0.3 in) or [min, max]")
            lo, hi = (parse_quantity(x, kind) for x in v)
            if lo > hi:
                raise ValueError(f"min {v[0]!r} exceeds max {v[1]!r}")
            if lo > 0 or hi < 0:
                raise ValueError("the nominal value (0) must lie inside [min, max]")
            if kind == "angle":
                _check_rotation_error(v, max(-lo, hi))
            return {"lo": lo, "hi": hi}
        tol = parse_quantity(v, kind)
        if tol < 0:
            raise ValueError(f"tolerance {v!r} is negative; write the half-width, e.g. '0.3 in'")
        lo, hi = -tol, tol
        if kind == "angle":
            _check_rotation_error(v, tol)
        return {"lo": lo, "hi": hi}

    return BeforeValidator(parse)


LengthBound = Annotated[Bound, _bound("length")]
AngleBound = Annotated[Bound, _bound("angle")]


class LinearConstraint(_Model):
    """A coupled constraint ``min ≤ Σ c_k · v_k ≤ max`` between a link's error parameters.

    Coefficients are numbers, or quantities that convert between kinds (``"2 cm/deg"`` on a
    rotation parameter gives a length). Every term must have the dimension of the bound.
    """

    terms: dict[str, float]
    min: float | None = None
    max: float | None = None
    kind: Literal["length", "angle"]

    @model_validator(mode="before")
    @classmethod
    def _parse(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            raise ValueError("a constraint is a mapping with 'terms' and 'min' and/or 'max'")
        raw_terms = data.get("terms")
        if not isinstance(raw_terms, dict) or not raw_terms:
            raise ValueError(
                "'terms' must map error parameters (x, y, z, rx, ry, rz) to coefficients"
            )
        if data.get("min") is None and data.get("max") is None:
            raise ValueError("a constraint needs 'min', 'max' or both")
        kind = _constraint_kind(data)
        terms: dict[str, float] = {}
        for param, coefficient in raw_terms.items():
            if param not in PARAMS:
                raise ValueError(
                    f"unknown error parameter {param!r}; use one of {', '.join(PARAMS)}"
                )
            terms[param] = _coefficient_si(param, coefficient, kind)
        out: dict[str, Any] = {"terms": terms, "kind": kind}
        for key in ("min", "max"):
            if data.get(key) is not None:
                out[key] = parse_quantity(data[key], kind)
        extra = set(data) - {"terms", "min", "max"}
        if extra:
            raise ValueError(f"unknown constraint field(s): {', '.join(sorted(extra))}")
        return out

    @model_validator(mode="after")
    def _ordered(self) -> LinearConstraint:
        if self.min is not None and self.max is not None and self.min > self.max:
            raise ValueError("constraint min exceeds max")
        return self


def _constraint_kind(data: dict[str, Any]) -> Literal["length", "angle"]:
    bound = data.get("max") if data.get("max") is not None else data.get("min")
    ureg = registry()
    q = read_quantity(bound)
    if q.unitless:
        raise ValueError(f"constraint bound {bound!r} has no unit")
    if q.dimensionality == ureg.meter.dimensionality:
        return "length"
    if q.dimensionality == ureg.radian.dimensionality:
        return "angle"
    raise ValueError(f"constraint bound {bound!r} must be a length or an angle")


def _coefficient_si(param: str, coefficient: Any, kind: Literal["length", "angle"]) -> float:
    """SI value of a constraint coefficient, checking that c · param has the bound's kind."""
    ureg = registry()
    param_kind = "length" if param in TRANSLATION_PARAMS else "angle"
    if isinstance(coefficient, bool):
        raise ValueError(f"coefficient of {param} must be a number or a quantity")
    if isinstance(coefficient, int | float):
        value = float(coefficient)
        if not math.isfinite(value):
            raise ValueError(f"coefficient of {param} is not finite")
        if param_kind != kind:
            raise ValueError(
                f"term {param} is a {param_kind} but the bound is a {kind}; give its coefficient "
                f"a unit, e.g. '1 cm/deg'"
            )
        return value
    q = read_quantity(coefficient)
    length_dim = ureg.meter.dimensionality
    if param_kind == kind and q.dimensionality == ureg.dimensionless.dimensionality:
        return si_magnitude(q, "", coefficient)
    if param_kind == "angle" and kind == "length" and q.dimensionality == length_dim:
        return si_magnitude(q, "m/rad", coefficient)
    if param_kind == "length" and kind == "angle" and q.dimensionality == 1 / length_dim:
        return si_magnitude(q, "rad/m", coefficient)
    raise ValueError(
        f"coefficient {coefficient!r} of {param} does not turn a {param_kind} into a {kind}"
    )


Distribution = Literal["uniform", "normal"]
"""How a bounded error is sampled in Monte Carlo (seed ch. IX, L7240–7242: uniform, or normal
with σ = tolerance/3 truncated at the tolerance); the choice is the production engineer's."""


class Uncertainty(_Model):
    """Bounded error parameters of one link, in the link's frame (seed Eqn 3.5.1, L2205).

    The true link is ``nominal ∘ transl(x, y, z) ∘ rot(x̂, rx) ∘ rot(ŷ, ry) ∘ rot(ẑ, rz)``.
    Unlisted parameters are exact. ``distribution`` is for Monte Carlo sampling: ``uniform`` on
    the feasible set, or ``normal`` with σ = tolerance/3 truncated at the tolerance (seed L7242).
    """

    x: LengthBound | None = None
    y: LengthBound | None = None
    z: LengthBound | None = None
    rx: AngleBound | None = None
    ry: AngleBound | None = None
    rz: AngleBound | None = None
    constraints: tuple[LinearConstraint, ...] = ()
    distribution: Distribution = "uniform"

    def bounds(self) -> dict[str, Bound]:
        """The bounded parameters in canonical order (x, y, z, rx, ry, rz)."""
        return {p: getattr(self, p) for p in PARAMS if getattr(self, p) is not None}

    def constraint_rows(self) -> tuple[list[list[float]], list[float]]:
        """``min ≤ c·v ≤ max`` as rows of ``A v ≤ b`` over :meth:`bounds`' order [SI]."""
        names = list(self.bounds())
        rows: list[list[float]] = []
        rhs: list[float] = []
        for c in self.constraints:
            row = [c.terms.get(n, 0.0) for n in names]
            if c.max is not None:
                rows.append(row)
                rhs.append(c.max)
            if c.min is not None:
                rows.append([-x for x in row])
                rhs.append(-c.min)
        return rows, rhs

    @model_validator(mode="after")
    def _constraints_use_bounded_params(self) -> Uncertainty:
        bounded = self.bounds()
        for i, c in enumerate(self.constraints):
            for p in c.terms:
                if p not in bounded:
                    raise ValueError(
                        f"constraints[{i}] uses {p}, which has no bound in this block; "
                        f"every error parameter must be bounded"
                    )
        return self


class BoxShape(_Model):
    """A rectangular body; frame origin at the centre of its bottom face, z up."""

    type: Literal["box"]
    size: tuple[PositiveLength, PositiveLength, PositiveLength]


class PinShape(_Model):
    """A pin; frame origin at the tip centre, z from the tip towards the head (seed L2030)."""

    type: Literal["pin"]
    length: PositiveLength
    diameter: PositiveLength
    tip_taper_length: NonNegativeLength
    tip_radius: NonNegativeLength
    mass: (
        Annotated[float, BeforeValidator(lambda v: parse_quantity(v, "mass")), Field(ge=0)] | None
    ) = None
    """[kg] kept with the task; the planner's models are kinematic and quasi-static (seed §3),
    so no figure depends on it."""

    @model_validator(mode="after")
    def _consistent(self) -> PinShape:
        if self.tip_radius > self.diameter / 2:
            raise ValueError("tip_radius is larger than the shaft radius")
        if self.tip_taper_length >= self.length:
            raise ValueError("tip_taper_length must be shorter than the pin")
        return self


class HoleShape(_Model):
    """A drilled hole; frame origin at the centre of its mouth, z along the outward normal."""

    type: Literal["hole"]
    diameter: PositiveLength
    depth: PositiveLength
    chamfer_width: NonNegativeLength = 0.0
    surface: str

    @model_validator(mode="after")
    def _chamfer_fits(self) -> HoleShape:
        # A 45° chamfer of radial width w is w deep: it must end above the hole's bottom.
        if self.chamfer_width >= self.depth:
            raise ValueError(
                f"chamfer_width {self.chamfer_width:.4g} m is not shallower than the hole "
                f"(depth {self.depth:.4g} m): a 45° chamfer of width w is w deep"
            )
        return self


class SurfaceShape(_Model):
    """A planar face; the outline polygon lies in the frame's xy plane (z = outward normal).

    The holes drilled into it are the hole features naming this surface; the tapping-place
    search (seed L2300–2330) measures distances to them and to the outline.
    """

    type: Literal["surface"]
    outline: tuple[tuple[Length, Length], ...]

    @field_validator("outline")
    @classmethod
    def _polygon(cls, v: tuple[tuple[float, float], ...]) -> tuple[tuple[float, float], ...]:
        if len(v) < 3:
            raise ValueError("an outline needs at least three vertices")
        area2 = sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in zip(v, v[1:] + v[:1], strict=True))
        if abs(area2) < 1e-12:
            raise ValueError("the outline has zero area")
        return v


class FixtureShape(_Model):
    """An open-topped box (seed A.1, Figure A.1): a cavity with a floor and four side walls.

    Frame origin at the centre of the inside floor, z up into the cavity. ``inside`` is the
    cavity (x, y, depth); ``wall`` and ``floor`` are the material thicknesses. Its named faces
    (``floor``, inner walls ``xpos`` … ``yneg``, underside ``bottom``), edges and corners are
    listed in :mod:`synth.models.features`.
    """

    type: Literal["fixture"]
    inside: tuple[PositiveLength, PositiveLength, PositiveLength]
    wall: PositiveLength
    floor: PositiveLength


Shape = Annotated[
    BoxShape | PinShape | HoleShape | SurfaceShape | FixtureShape, Field(discriminator="type")
]

OBJECT_SHAPES = frozenset({"box", "pin", "fixture"})
FEATURE_SHAPES = frozenset({"hole", "surface"})


class FrameSpec(_Model):
    """One node of the frame tree and the link to its parent."""

    name: str
    al_name: str
    parent: str = WORLD
    pose: Pose = Pose()
    kind: Literal["rigid", "nonrigid", "independent"] = "nonrigid"
    uncertainty: Uncertainty | None = None
    shape: Shape | None = None

    @field_validator("name")
    @classmethod
    def _name(cls, v: str) -> str:
        if _FRAME_NAME.fullmatch(v) is None:
            raise ValueError(
                f"{v!r} is not a frame name: an ASCII letter followed by letters, digits, '_' "
                "or '-', with no space or control character"
            )
        if v == WORLD:
            raise ValueError("'world' is the root frame and cannot be redefined")
        return v

    @field_validator("al_name")
    @classmethod
    def _al_name(cls, v: str) -> str:
        return _check_al_name(v)


DEFAULT_FRICTION = 0.3
"""[1] pin–hole friction coefficient when the task gives none: machined, lightly oiled steel
on steel (Marks' Standard Handbook for Mechanical Engineers, Table 3.2.1: steel on steel 0.74
dry static, 0.1–0.2 greasy; 0.3 is a cautious value for oiled parts). Dry parts should state
theirs (``insertion.friction``)."""


MAX_FRICTION = 2.0
"""[1] the largest pin–hole friction coefficient a task may give (rubber on steel, about 2)."""


class InsertionSpec(_Model):
    """Which pin goes into which hole, and the insertion parameters of seed §4.2 (L1990–2010).

    Unset parameters are derived from the geometry by :func:`synth.models.insertion.derive`;
    ``friction`` (μ) sets the wedging limit Δθ_ok never exceeds.
    """

    pin: str
    hole: str
    start_hole: str | None = None
    direction: Literal["parallel", "antiparallel"] = "parallel"
    d_f: NonNegativeLength | None = None
    d_s: NonNegativeLength | None = None
    dr_ok: Length | None = None
    """[m] Δr_ok, the lateral error an insertion tolerates (seed L1963); > 0, since the search
    spaces its rings by it."""
    dtheta_ok: Annotated[float, BeforeValidator(_angle), Field(ge=0)] | None = None
    friction: Annotated[float, Field(ge=0, allow_inf_nan=False)] = DEFAULT_FRICTION
    """[1] pin–hole friction coefficient μ: the planner's wedging limit
    (:mod:`synth.models.jamming`) and the replay's (:mod:`synth.replay.wedging`)."""

    @field_validator("friction")
    @classmethod
    def _friction_physical(cls, v: float) -> float:
        # the highest coefficients of engineering pairs, clean dry metals and rubber on steel,
        # lie near 1–2 (Marks' Table 3.2.1); a larger μ is a slip of the pen (50 for 0.50)
        if v > MAX_FRICTION:
            raise ValueError(
                f"friction μ = {v:g} is above {MAX_FRICTION:g}: no engineering pair of "
                "materials grips that hard (dry steel 0.6–0.8, rubber on steel up to about 2); "
                "give the coefficient, not a percentage"
            )
        return v

    @field_validator("dr_ok")
    @classmethod
    def _dr_ok_positive(cls, v: float | None) -> float | None:
        if v is not None and not v > 0:
            raise ValueError(
                f"dr_ok must be > 0 (got {v:g} m): the search spaces its rings by Δr_ok, and "
                "an insertion that tolerates no lateral error cannot succeed"
            )
        return v


class SequenceSpec(_Model):
    """Several insertions in one task (seed IV ch. 5, L2870–2890): the steps and their order.

    ``order: fixed`` runs the steps as listed; ``free`` lets the planner choose the order with
    the least expected time. A plain list of steps in the task file means ``fixed``.
    """

    order: Literal["fixed", "free"] = "fixed"
    steps: tuple[InsertionSpec, ...]

    @model_validator(mode="before")
    @classmethod
    def _plain_list(cls, data: Any) -> Any:
        return {"steps": data} if isinstance(data, list | tuple) else data

    @field_validator("steps")
    @classmethod
    def _some(cls, v: tuple[InsertionSpec, ...]) -> tuple[InsertionSpec, ...]:
        if not v:
            raise ValueError("a sequence needs at least one step")
        pins = [s.pin for s in v]
        twice = sorted({p for p in pins if pins.count(p) > 1})
        if twice:
            raise ValueError(f"pin {twice[0]!r} is inserted twice; each step moves its own pin")
        holes = [s.hole for s in v]
        filled = sorted({h for h in holes if holes.count(h) > 1})
        if filled:
            raise ValueError(f"hole {filled[0]!r} receives two pins")
        return v


RATE_FIELDS = ("velocity_limits", "acceleration_limits", "jerk_limits")
"""The arm's rate overrides, by order: velocity, acceleration, jerk."""


def _joint_rates(order: int) -> Any:
    """Per-joint rate limits with units, e.g. ``["2 rad/s", "50 cm/s"]`` → SI floats.

    ``order`` is the power of time: 1 velocity ([rad/s] or [m/s]), 2 acceleration, 3 jerk. A
    revolute joint takes an angular rate, a prismatic joint a linear one; both are stored as SI
    magnitudes in joint order, and :func:`synth.models.arm.load_arm` checks the count.
    """

    def parse(v: Any) -> Any:
        if v is None:
            return None
        if isinstance(v, str) or not isinstance(v, list | tuple):
            raise ValueError("give one rate per joint as a list, e.g. ['2 rad/s', '0.5 m/s']")
        out = []
        for item in v:
            if isinstance(item, bool) or not isinstance(item, str):
                raise ValueError(f"{item!r} has no unit; write e.g. '2 rad/s' or '0.5 m/s'")
            out.append(rate_si(item, order))
        return tuple(out)

    return BeforeValidator(parse)


class ArmSpec(_Model):
    """The arm model: a built-in arm (``model: stanford``, ``ur5``, ``panda``, …) or a URDF.

    ``model`` names the seed's Stanford arm or an arm of example-robot-data under its loader's
    name (:data:`synth.models.catalog.ARM_MODELS`; installed by the ``robots`` extra); ``urdf``
    any other arm. ``base`` places the arm's base frame in the world. ``tool_frame`` names the
    URDF frame that AL's hand frame (BHAND/BMANIP) is bound to, and ``tool_offset`` the hand
    frame's pose in it (e.g. from a bare flange such as the UR5's ``tool0`` to the point
    between the finger pads); a built-in arm has defaults for both. ``srdf`` lists link pairs
    whose collisions are disabled (``<disable_collisions>``). ``fingers`` names a URDF's own
    finger joints: they become the hand instead of synth's parametric one.
    ``velocity_limits``, ``acceleration_limits``, ``jerk_limits`` override the model's per-joint
    limits (one entry per joint, with units; SI floats inside).
    """

    model: str | None = None
    urdf: str | None = None
    tool_frame: str | None = None
    package_dirs: tuple[str, ...] = ()
    base: Pose = Pose()
    tool_offset: Pose = Pose()
    srdf: str | None = None
    fingers: tuple[str, ...] = ()
    velocity_limits: Annotated[tuple[float, ...] | None, _joint_rates(1)] = None
    acceleration_limits: Annotated[tuple[float, ...] | None, _joint_rates(2)] = None
    jerk_limits: Annotated[tuple[float, ...] | None, _joint_rates(3)] = None
    _rate_kinds: dict[str, tuple[str | None, ...]] = PrivateAttr(default_factory=dict)
    """Per rate field, the joint kind each entry's unit was written for (angular: revolute,
    linear: prismatic), kept from the task's text for :func:`synth.models.arm.load_arm`."""

    @model_validator(mode="wrap")
    @classmethod
    def _keep_rate_kinds(cls, data: Any, handler: Any) -> Any:
        spec = handler(data)
        if isinstance(data, dict):
            for order, name in enumerate(RATE_FIELDS, start=1):
                raw = data.get(name)
                if isinstance(raw, list | tuple):
                    spec._rate_kinds[name] = tuple(rate_kind(v, order) for v in raw)
        return spec

    def rate_kinds(self, name: str) -> tuple[str | None, ...]:
        """The joint kinds the entries of rate field ``name`` were written for (module text)."""
        return self._rate_kinds.get(name, ())

    @field_validator("model")
    @classmethod
    def _known_model(cls, v: str | None) -> str | None:
        if v is not None and v not in ARM_MODELS:
            raise ValueError(f"unknown arm model {v!r}; built-in arms: {', '.join(ARM_MODELS)}")
        return v

    @model_validator(mode="after")
    def _one_source(self) -> ArmSpec:
        if (self.model is None) == (self.urdf is None):
            raise ValueError(
                "name exactly one arm: 'model: NAME' (e.g. stanford, ur5) or 'urdf: PATH'"
            )
        if self.urdf is not None and not self.tool_frame:
            raise ValueError("a URDF arm needs 'tool_frame', the frame the hand is bound to")
        if self.model is not None:
            extra = [f for f in ("srdf", "package_dirs", "fingers") if f in self.model_fields_set]
            if extra:
                raise ValueError(
                    f"a built-in arm ('model: {self.model}') brings its own files and fingers; "
                    f"remove {', '.join(extra)} or name the URDF with 'urdf:'"
                )
        return self


class HandSpec(_Model):
    """Two-finger hand geometry (seed L1984: fingers open through about 4.5 in).

    In the hand frame (origin between the finger pads, z the approach vector) the fingers close
    along x: each is a plate ``finger_thickness`` thick, as wide as a pad, reaching
    ``finger_length`` back to the palm, a box of ``palm_size`` (x, y, z) behind them.
    """

    max_opening: PositiveLength = 4.5 * INCH
    finger_pad_radius: PositiveLength = 0.25 * INCH
    finger_length: PositiveLength = 2.0 * INCH
    finger_thickness: PositiveLength = 0.01
    palm_size: tuple[PositiveLength, PositiveLength, PositiveLength] = (0.14, 0.05, 0.03)


class ParkSpec(_Model):
    """The arm's park frame (e.g. ``BPARK``), in world coordinates.

    ``al_name`` is any AL name a frame may take, or ``BPARK`` (:func:`al_name_problem`).
    """

    al_name: str = "BPARK"
    pose: Pose

    @field_validator("al_name")
    @classmethod
    def _al(cls, v: str) -> str:
        return _check_al_name(v, role="park")


class ManipulatorSpec(_Model):
    """The manipulator: arm model, hand, park frame and hand positioning errors.

    ``al_name`` is any AL name a frame may take, or one of the blue arm's names (``BMANIP``,
    ``BLUE``, ``BARM``, ``BHAND``, ``BFINGERS``), never a constant such as ``TRUE``.
    """

    al_name: str = "BMANIP"
    arm: ArmSpec
    hand: HandSpec = HandSpec()
    park: ParkSpec
    hand_error: Uncertainty | None = None

    @field_validator("al_name")
    @classmethod
    def _al(cls, v: str) -> str:
        return _check_al_name(v, role="arm")


class ProofSpec(_Model):
    """How a program for this task must be proven (``synth plan`` options override it).

    ``min_success``: the success rate [1] the replay's Monte Carlo proof must reach;
    ``trials``: the proof's budget of sampled worlds (0: the nominal replay only).
    """

    min_success: float = Field(default=0.99, ge=0.0, le=1.0)
    trials: int | None = Field(default=None, ge=0, le=1_000_000)


class TaskSpec(_Model):
    """A whole task: frame tree, insertion, manipulator, contacts and the proof it needs."""

    name: str
    description: str = ""
    frames: tuple[FrameSpec, ...]
    _lines: dict[PathKey, int] = PrivateAttr(default_factory=dict)
    """The YAML line of each field of the task's text (none for a spec built in Python)."""
    insertion: InsertionSpec | None = None
    insertions: SequenceSpec | None = None
    manipulator: ManipulatorSpec | None = None
    contacts: tuple[ContactSpec, ...] = ()
    proof: ProofSpec | None = None

    @field_validator("frames")
    @classmethod
    def _nonempty(cls, v: tuple[FrameSpec, ...]) -> tuple[FrameSpec, ...]:
        if not v:
            raise ValueError("a task needs at least one frame")
        return v

    @model_validator(mode="after")
    def _one_insertion_form(self) -> TaskSpec:
        if self.insertion is not None and self.insertions is not None:
            raise ValueError("give 'insertion' (one step) or 'insertions' (a sequence), not both")
        return self

    def remember_lines(self, lines: dict[PathKey, int]) -> None:
        """Keep the YAML lines of the task's fields, for errors found after loading."""
        self._lines = dict(lines)

    def line_of(self, field: str) -> int | None:
        """The YAML line of ``field`` (``'frames[2].pose'``), or of its nearest parent given."""
        return line_of(parse_path(field), self._lines)

    @property
    def steps(self) -> tuple[InsertionSpec, ...]:
        """The insertions in their listed order: ``insertions.steps``, or ``(insertion,)``."""
        if self.insertions is not None:
            return self.insertions.steps
        return () if self.insertion is None else (self.insertion,)

    @property
    def is_sequence(self) -> bool:
        """Whether the task has more than one insertion."""
        return len(self.steps) > 1

    def step(self, insertion: InsertionSpec) -> TaskSpec:
        """The single-insertion task of one step (the same frames, arm and proof)."""
        return self.model_copy(update={"insertion": insertion, "insertions": None})

    def with_distribution(self, distribution: Distribution) -> TaskSpec:
        """The task with every error block (frames and hand) sampled from ``distribution``.

        For sensitivity studies of Monte Carlo rates (seed L7240: "the shape of the distribution
        function depends on the manufacturing process"); the bounds are unchanged, so the
        planner's worst-case figures are too.
        """

        def swap(block: Uncertainty | None) -> Uncertainty | None:
            return (
                None if block is None else block.model_copy(update={"distribution": distribution})
            )

        frames = tuple(
            f.model_copy(update={"uncertainty": swap(f.uncertainty)}) for f in self.frames
        )
        manipulator = self.manipulator
        if manipulator is not None:
            manipulator = manipulator.model_copy(
                update={"hand_error": swap(manipulator.hand_error)}
            )
        return self.model_copy(update={"frames": frames, "manipulator": manipulator})
