"""The task specification: a pydantic schema for ``task.yaml``, SI units inside.

A task describes a pin-in-hole workcell (seed ch. IV, L1120–3290):

* ``frames`` — a tree of named objects and features. Every link has a parent (another frame or
  ``world``), a nominal pose relative to it, a kind (``rigid`` / ``nonrigid`` / ``independent``,
  as POINTY defines affixments, seed L6330 and L6840–6850) and an optional uncertainty block.
* ``insertion`` — which pin goes into which hole, with the parameters of seed §4.2
  (L1990–2010): direction, d_f, d_s, Δr_ok, Δθ_ok, derived from geometry unless overridden.
* ``manipulator`` — the arm model, its park frame and the hand's positioning errors
  (:mod:`synth.models.manipulator`).

Its records are built from the field types of :mod:`synth.models.spec_fields` and the error
bounds of :mod:`synth.models.uncertainty`.

Every dimensioned number carries its unit (``"3.85 cm"``, ``"5 deg"``), parsed by
:mod:`synth.units`; the validated model holds SI floats (m, rad, N). ``docs/task-spec.md`` is the
annotated reference. Semantic checks that need the whole tree (unknown parents, cycles, name
clashes, infeasible constraints) live in :mod:`synth.models.loader`, which can point at YAML
lines.
"""

from __future__ import annotations

import contextlib
import re
from collections.abc import Iterator
from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field, PrivateAttr, field_validator, model_validator

from synth.exceptions import SpecError
from synth.models.contacts import ContactSpec
from synth.models.manipulator import ManipulatorSpec
from synth.models.spec_fields import (
    Length,
    NonNegativeAngle,
    NonNegativeLength,
    Pose,
    PositiveLength,
    SpecModel,
    check_al_name,
)
from synth.models.uncertainty import Distribution, Uncertainty
from synth.models.yamlread import PathKey, line_of, parse_path
from synth.units import parse_quantity

_FRAME_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_-]*", re.ASCII)
"""A frame's own name (not its AL name): matched in full, so no trailing newline gets through."""

WORLD = "world"
"""Name of the root frame (the work station / table frame)."""


class BoxShape(SpecModel):
    """A rectangular body; frame origin at the centre of its bottom face, z up."""

    type: Literal["box"]
    size: tuple[PositiveLength, PositiveLength, PositiveLength]


class PinShape(SpecModel):
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


class HoleShape(SpecModel):
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


class SurfaceShape(SpecModel):
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


class FixtureShape(SpecModel):
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


class FrameSpec(SpecModel):
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
        return check_al_name(v)


DEFAULT_FRICTION = 0.3
"""[1] pin–hole friction coefficient when the task gives none: machined, lightly oiled steel
on steel (Marks' Standard Handbook for Mechanical Engineers, Table 3.2.1: steel on steel 0.74
dry static, 0.1–0.2 greasy; 0.3 is a cautious value for oiled parts). Dry parts should state
theirs (``insertion.friction``)."""


MAX_FRICTION = 2.0
"""[1] the largest pin–hole friction coefficient a task may give (rubber on steel, about 2)."""


class InsertionSpec(SpecModel):
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
    dtheta_ok: NonNegativeAngle | None = None
    # strict: a quoted '0.3' is text and refused; a slip such as '0.3 %' or '30%' would be too
    friction: Annotated[float, Field(strict=True, ge=0, allow_inf_nan=False)] = DEFAULT_FRICTION
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


class SequenceSpec(SpecModel):
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


class ProofSpec(SpecModel):
    """How a program for this task must be proven (``synth plan`` options override it).

    ``min_success``: the success rate [1] the replay's Monte Carlo proof must reach;
    ``trials``: the proof's budget of sampled worlds (0: the nominal replay only).
    """

    min_success: float = Field(default=0.99, strict=True, ge=0.0, le=1.0)
    trials: int | None = Field(default=None, strict=True, ge=0, le=1_000_000)


class TaskSpec(SpecModel):
    """A whole task: frame tree, insertion, manipulator, contacts and the proof it needs."""

    name: str
    description: str = ""
    frames: tuple[FrameSpec, ...]
    _lines: dict[PathKey, int] = PrivateAttr(default_factory=dict)
    """The YAML line of each field of the task's text (none for a spec built in Python)."""
    _step_path: str | None = PrivateAttr(default=None)
    """Where a step's ``insertion`` stands in the text, ``insertions.steps[i]`` or, given as a
    plain list, ``insertions[i]`` (:meth:`step`)."""
    insertion: InsertionSpec | None = None
    insertions: SequenceSpec | None = None
    manipulator: ManipulatorSpec | None = None
    contacts: tuple[ContactSpec, ...] = ()
    proof: ProofSpec | None = None

    @field_validator("name")
    @classmethod
    def _named(cls, v: str) -> str:
        # The name is how messages, `synth plan --json` and the service's plan list tell
        # tasks apart; a blank or multi-line one would print as nothing, or break a line.
        if not v.strip():
            raise ValueError("a task needs a name (it was blank)")
        if not v.isprintable():
            raise ValueError(f"a task's name is one printable line, got {v!r}")
        return v

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

    def field_path(self, field: str) -> str:
        """``field`` as the task's text names it.

        A step's single task (:meth:`step`) has its insertion at ``insertion``; the text has it
        at ``insertions.steps[i]``, where its refusals must point.
        """
        if self._step_path is not None and (field == "insertion" or field.startswith("insertion.")):
            return self._step_path + field[len("insertion") :]
        return field

    def line_of(self, field: str) -> int | None:
        """The YAML line of ``field`` (``'frames[2].pose'``), or of its nearest parent given."""
        return line_of(parse_path(self.field_path(field)), self._lines)

    @contextlib.contextmanager
    def lines_on_errors(self) -> Iterator[None]:
        """A :class:`SpecError` raised inside without a line gets its field's line here.

        For checks made after loading by code that knows the field but not the file (the
        service's model paths, the park): their refusals had no line where every other has. A
        step's refusal at ``insertion.…`` is moved to where the text has it
        (:meth:`field_path`): a step's too-shallow d_f was refused at "insertion.d_f (line 1)".
        """
        try:
            yield
        except SpecError as error:
            path = self.field_path(error.path)
            if error.line is not None and path == error.path:
                raise
            raise SpecError(path, error.detail, self.line_of(path)) from None

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
        single = self.model_copy(update={"insertion": insertion, "insertions": None})
        if self.insertions is not None:
            steps = self.insertions.steps
            index = next((i for i, s in enumerate(steps) if s is insertion), None)
            if index is None and insertion in steps:
                index = steps.index(insertion)
            if index is not None:
                plain = ("insertions", index) in self._lines  # the text's plain list of steps
                where = f"insertions[{index}]" if plain else f"insertions.steps[{index}]"
                single._step_path = where
        return single

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
