"""What a seated pin teaches: the part's uncertainty once a pin stands in one of its holes.

Seed IV ch. 5 (L2870–2890): "Inserting the first pin gives us information about the box
location. Since this information can be used to reduce the search required for the second
insertion …". When a pin has bottomed out in hole H of a part P, the hand's reading puts the
pin's end (the seat) at m = s_true + ε, where s_true is the true seat and ε the reading's
error: the hand positioning error carried to the pin's end, the pin's offset in the hand, and
the pin's play in the hole,

    |ε| ≤ ε_max = ‖t_hand‖ + ‖θ_hand‖·d + ‖g‖ + (D_hole − D_pin)/2,

with t_hand, θ_hand the hand-error block's translation and rotation bounds (vector norms), d
the grasp distance (the hand origin to the pin's end) and g the pin end's residual in the hand
after CENTER (the grasp determination's translation bounds, from the start location: the hand
reads the pin where the nominal grip puts it, and CENTER registers it along the fingers only).
Left out, a pin from a rack known to ±0.4 cm, 0.48 cm off across the pads, corrected its
plate to ±0.10 cm: the next step was planned with no search and missed in 9 of 200 worlds of
that rack's edge. The program then corrects P by the
measured offset along the translation axes P's block bounds more loosely than ε_max (elsewhere
the reading would be the worse knowledge), P ← P·TRANS(NILROTN, Δ) with Δ the
offset in P's axes (translation only: one point says nothing about P's turn about it; an axis
P was exact in stays uncorrected, so the reading's error never enters it), and P's holes,
affixed to it, move with it.

Let P's error be the seed's block, True = Nominal ∘ transl(t) ∘ R(ω), with the seat at h in P's
frame. Relative to the corrected frame C the true part is t' = −(R − I)·h − ε (in P's axes)
with the same rotation ω. To first order (R − I)·h = ω × h, so for each axis i

    |t'_i + (ω × h)_i| ≤ ε_max + ρ,   ρ = ‖h‖·Θ²,  Θ = ‖(ω bounds)‖,

where ρ bounds the second-order terms (the exponential's, ≤ ‖h‖·Θ²/2, and the composition
rot(x̂)·rot(ŷ)·rot(ẑ) against exp([ω]×), ≤ ‖h‖·Θ²/2), so the rows are certified. These rows
join the part's block as linear constraints (``Uncertainty.constraints``); each translation
also gets the box bound |t'_i| ≤ ε_max + ρ + Σ_j |∂(ω × h)_i/∂ω_j|·θ_j,max that they imply. The
rotations keep their bounds, and the old block's constraints on rotations only. The next
step's footprint, tap and search are then the LP's over this block.

Only a part that is the single uncertain link between the hole and the world is corrected (a
box on the table; not a hole toleranced inside an uncertain box, nor a part located by
contacts, whose block the planner derives).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from pinocchio import rpy as pin_rpy

from synth.models.believed import believed_graph
from synth.models.graph import AttributeGraph
from synth.models.insertion import derive
from synth.models.spec import WORLD, HoleShape, InsertionSpec, PinShape, TaskSpec
from synth.models.spec_fields import Pose, Rotation
from synth.models.uncertainty import (
    ROTATION_PARAMS,
    TRANSLATION_PARAMS,
    Bound,
    LinearConstraint,
    Uncertainty,
)

__all__ = ["SeatKnowledge", "after_seat", "seat_error", "seated"]


@dataclass(frozen=True)
class SeatKnowledge:
    """The part a seated pin located, and the task as the next step believes it.

    ``part``/``part_al`` name the corrected part, ``corrected`` the translation axes (of its
    frame) the correction moves it along, ``seat`` [m] is h (the seat in the part's
    frame), ``epsilon`` [m] the reading's error bound ε_max, ``before``/``after`` the part's
    block, and ``spec`` the task with the pin standing in its hole and ``after`` in place.
    """

    part: str
    part_al: str
    hole_al: str
    pin_al: str
    d_f: float
    corrected: tuple[str, ...]
    seat: tuple[float, float, float]
    epsilon: float
    before: Uncertainty
    after: Uncertainty
    spec: TaskSpec


def pin_se3_z(z: float) -> pin.SE3:
    """trans(NILROTN, (0, 0, z)) [m]."""
    return pin.SE3(np.eye(3), np.array([0.0, 0.0, z]))


def seated(spec: TaskSpec, insertion: InsertionSpec) -> TaskSpec:
    """The task with the insertion's pin standing in its hole, tip d_f deep (nothing learnt)."""
    graph = AttributeGraph(spec)
    pin_name, hole = graph.resolve(insertion.pin), graph.resolve(insertion.hole)
    d_f = derive(graph, insertion).d_f
    pose = Pose.model_validate({"translation": ["0 m", "0 m", f"{-d_f!r} m"]})
    frames = tuple(
        f.model_copy(update={"parent": hole, "pose": pose}) if f.name == pin_name else f
        for f in spec.frames
    )
    return spec.model_copy(update={"frames": frames})


def seat_error(
    spec: TaskSpec,
    insertion: InsertionSpec,
    grasp_distance: float,
    grip: Sequence[tuple[str, float, float]] = (),
) -> float:
    """ε_max [m] (module docstring): the hand's error, the pin's offset in it, the pin's play.

    ``grip`` is the grasp determination's (name, lo, hi); its x, y and z are counted.
    """
    graph = AttributeGraph(spec)
    pin_shape = graph.nodes[graph.resolve(insertion.pin)].shape
    hole_shape = graph.nodes[graph.resolve(insertion.hole)].shape
    assert isinstance(pin_shape, PinShape) and isinstance(hole_shape, HoleShape)
    play = max(0.0, (hole_shape.diameter - pin_shape.diameter) / 2)
    offset = math.sqrt(sum(max(-lo, hi) ** 2 for n, lo, hi in grip if n in TRANSLATION_PARAMS))
    hand = spec.manipulator.hand_error if spec.manipulator is not None else None
    if hand is None:
        return offset + play
    bounds = hand.bounds()

    def norm(params: tuple[str, ...]) -> float:
        return math.sqrt(sum(max(-b.lo, b.hi) ** 2 for p, b in bounds.items() if p in params))

    return norm(TRANSLATION_PARAMS) + norm(ROTATION_PARAMS) * grasp_distance + offset + play


def _corrected_part(graph: AttributeGraph, hole: str) -> str | None:
    """The single uncertain link between ``hole`` and the world, if it is the hole's part."""
    uncertain = []
    for name in graph.ancestors(hole):
        block = graph.links[name].uncertainty if name != WORLD else None
        if block is not None and block.bounds():
            uncertain.append(name)
    if len(uncertain) != 1 or uncertain[0] == hole:
        return None
    return uncertain[0]


def _cross_coefficients(h: np.ndarray) -> dict[str, dict[str, float]]:
    """∂(ω × h)_i / ∂ω_j: (ω × h) = (ry·h_z − rz·h_y, rz·h_x − rx·h_z, rx·h_y − ry·h_x)."""
    hx, hy, hz = (float(v) for v in h)
    return {
        "x": {"ry": hz, "rz": -hy},
        "y": {"rz": hx, "rx": -hz},
        "z": {"rx": hy, "ry": -hx},
    }


def after_seat(
    spec: TaskSpec,
    insertion: InsertionSpec,
    grasp_distance: float,
    grip: Sequence[tuple[str, float, float]] = (),
) -> SeatKnowledge | None:
    """The knowledge a seated ``insertion`` gives (module docstring); None if nothing is learnt.

    ``grip`` is the step's grasp determination (the pin's residual in the hand, :func:`seat_error`).

    A part located by contacts is read at its derived pose and block (:func:`believed_graph`),
    and the next step's task holds it as placed with its corrected block.
    """
    graph = believed_graph(spec)
    spec = graph.spec
    hole = graph.resolve(insertion.hole)
    part = _corrected_part(graph, hole)
    if part is None:
        return None
    before = graph.links[part].uncertainty
    assert before is not None
    d_f = derive(graph, insertion).d_f
    seat_in_part = graph.relative(part, hole).act(np.array([0.0, 0.0, -d_f]))
    epsilon = seat_error(spec, insertion, grasp_distance, grip)
    rotations = {p: b for p, b in before.bounds().items() if p in ROTATION_PARAMS}
    theta = math.sqrt(sum(max(-b.lo, b.hi) ** 2 for b in rotations.values()))
    rho = float(np.linalg.norm(seat_in_part)) * theta**2
    half = epsilon + rho
    coefficients = _cross_coefficients(seat_in_part)
    # max |(ω × h)_i| over the rotation bounds, per translation axis i
    reach = {
        axis: sum(
            abs(c) * max(-rotations[j].lo, rotations[j].hi)
            for j, c in coefficients[axis].items()
            if j in rotations
        )
        for axis in TRANSLATION_PARAMS
    }
    fields: dict[str, Bound] = dict(rotations)
    constraints: list[LinearConstraint] = []
    # An axis is corrected only where the part is known worse than the reading: else the
    # reading's error would replace a smaller one.
    known = before.bounds()
    corrected = tuple(
        a for a in TRANSLATION_PARAMS if a in known and max(-known[a].lo, known[a].hi) > epsilon
    )
    for axis in corrected:
        terms = {j: c for j, c in coefficients[axis].items() if j in rotations and c != 0.0}
        fields[axis] = Bound(lo=-(half + reach[axis]), hi=half + reach[axis])
        if terms:
            constraints.append(
                LinearConstraint.model_construct(
                    terms={axis: 1.0, **terms}, min=-half, max=half, kind="length"
                )
            )
    # An uncorrected axis keeps its bound, and a constraint survives when it touches none of the
    # corrected axes (their parameters now mean the error relative to the corrected frame).
    for axis in TRANSLATION_PARAMS:
        if axis in known and axis not in corrected:
            fields[axis] = known[axis]
    kept = [c for c in before.constraints if not any(p in corrected for p in c.terms)]
    after = Uncertainty.model_construct(
        None,
        constraints=(*constraints, *kept),
        distribution=before.distribution,
        **fields,
    )
    pin_name = graph.resolve(insertion.pin)
    # The seated pin itself is where the reading put it, to within ε along the corrected axes
    # (along the others, where the part's own error and turn put it): a solid of its own.
    pin_bounds: dict[str, Bound] = {}
    for axis in TRANSLATION_PARAMS:
        rotation_reach = reach[axis]
        prior = max(-known[axis].lo, known[axis].hi) if axis in known else 0.0
        if axis in corrected:
            extent = half
        elif prior or rotation_reach:
            extent = prior + rotation_reach + (rho if rotation_reach else 0.0)
        else:
            extent = 0.0
        if extent > 0.0:
            pin_bounds[axis] = Bound(lo=-extent, hi=extent)
    world_seat = graph.world_from(hole) * pin_se3_z(-d_f)
    roll, pitch, yaw = (float(v) for v in pin_rpy.matrixToRpy(world_seat.rotation))
    pin_pose = Pose.model_construct(
        translation=tuple(float(v) for v in world_seat.translation),
        rotation=tuple(
            Rotation.model_construct(axis=a, angle=v)
            for a, v in (("z", yaw), ("y", pitch), ("x", roll))
            if abs(v) > 1e-15
        ),
    )
    pin_block = Uncertainty.model_construct(
        None, constraints=(), distribution=before.distribution, **pin_bounds
    )
    located = []
    for f in spec.frames:
        if f.name == part:
            f = f.model_copy(update={"uncertainty": after})
        elif f.name == pin_name:
            f = f.model_copy(
                update={"parent": WORLD, "pose": pin_pose, "uncertainty": pin_block or None}
            )
        located.append(f)
    next_spec = spec.model_copy(update={"frames": tuple(located)})
    return SeatKnowledge(
        part=part,
        part_al=graph.al_names[part],
        hole_al=graph.al_names[hole],
        pin_al=graph.al_names[pin_name],
        d_f=d_f,
        corrected=corrected,
        seat=tuple(float(v) for v in seat_in_part),  # type: ignore[arg-type]
        epsilon=epsilon,
        before=before,
        after=after,
        spec=next_spec,
    )
