"""Load a task YAML into a validated :class:`~synth.models.spec.TaskSpec`.

I/O lives here, at the edge. Every problem becomes one :class:`~synth.exceptions.SpecError`
naming the field path and, where the YAML has one, the line: schema errors from pydantic, and
the checks that need the whole tree (unknown parents, cycles, duplicate names, dangling
references, infeasible constraint sets).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import coal
import numpy as np
import pinocchio as pin
from pydantic import ValidationError
from scipy.optimize import linprog

from synth.exceptions import FrameLookupError, SpecError
from synth.models.arm.bodies import z_range
from synth.models.features import Face, box_features, check_contacts
from synth.models.graph import AttributeGraph
from synth.models.insertion import derived_d_f
from synth.models.jamming import fit_problem
from synth.models.meshes import hole_problem
from synth.models.spec import WORLD, FrameSpec, HoleShape, InsertionSpec, PinShape, TaskSpec
from synth.models.uncertainty import PARAMS, Uncertainty
from synth.models.yamlread import (
    DEFAULT_LIMITS,
    PathKey,
    YamlLimits,
    format_path,
    line_of,
    read_yaml,
)


def load_task(path: str | Path, *, limits: YamlLimits = DEFAULT_LIMITS) -> TaskSpec:
    """Read and validate a task file; raise :class:`SpecError` on any problem.

    At most ``limits.max_bytes + 1`` bytes are read, so a huge file (or ``/dev/zero``) is refused
    without being read whole.
    """
    p = Path(path)
    try:
        with p.open("rb") as f:
            raw = f.read(limits.max_bytes + 1)
        text = raw.decode("utf-8")
    except FileNotFoundError:
        raise SpecError(str(p), "no such task file") from None
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        column = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
        raise SpecError(
            str(p),
            f"byte 0x{raw[exc.start]:02x} at column {column} is not UTF-8: a task file is UTF-8 "
            "text (save it as UTF-8)",
            line,
        ) from None
    except OSError as exc:
        raise SpecError(str(p), f"cannot read task file: {exc}") from None
    if len(raw) > limits.max_bytes:
        raise SpecError(str(p), f"the task file is over the limit of {limits.max_bytes} bytes")
    return parse_task(text, source=str(p), limits=limits)


def parse_task(
    text: str, *, source: str = "<task>", limits: YamlLimits = DEFAULT_LIMITS
) -> TaskSpec:
    """Validate task YAML text (or JSON, which is YAML) into a :class:`TaskSpec`.

    The text is parsed once, under ``limits`` (size, nesting, list length, aliases and their
    expansion: :mod:`synth.models.yamlread`); the CLI and the service both come through here.
    """
    doc = read_yaml(text, source=source, limits=limits)
    if not isinstance(doc.data, dict):
        raise SpecError("", "a task is a YAML mapping with 'name' and 'frames'", 1)
    return validate_task(doc.data, doc.lines)


def validate_task(data: dict[str, Any], lines: dict[PathKey, int] | None = None) -> TaskSpec:
    """Validate an already-parsed mapping (e.g. a JSON request body) into a :class:`TaskSpec`."""
    lines = _plain_steps_lines(data, lines or {})
    if "insertion" in data and "insertions" in data:
        # TaskSpec refuses it too, at the task's root: here its field and line are known
        raise SpecError(
            "insertions",
            "give 'insertion' (one step) or 'insertions' (a sequence), not both",
            line_of(("insertions",), lines),
        )
    try:
        spec = TaskSpec.model_validate(data)
    except ValidationError as exc:
        err = _first_error(exc.errors(include_url=False))
        loc = _strip_union_tags(err["loc"])
        message = _message(err)
        line = line_of(loc, lines)
        if isinstance(data.get("insertions"), list) and loc[:2] == ("insertions", "steps"):
            loc = ("insertions", *loc[2:])  # the path as written: a plain list of steps
        raise SpecError(format_path(loc), message, line) from None
    check_task(spec, lines)
    spec.remember_lines(lines)
    return spec


def _plain_steps_lines(data: dict[str, Any], lines: dict[PathKey, int]) -> dict[PathKey, int]:
    """``lines`` with ``insertions.steps[i]…`` for a plain list of steps, ``insertions[i]…``.

    A plain list means ``{order: fixed, steps: [...]}`` (:class:`SequenceSpec`), and every
    field of its steps is checked under ``steps``: without these, a step's fault was put at
    the line of ``insertions:`` (the fourth hunt: line 104 for a unit missing on line 117).
    """
    if not isinstance(data.get("insertions"), list):
        return lines
    aliased = dict(lines)
    for key, line in lines.items():
        if len(key) > 1 and key[0] == "insertions" and isinstance(key[1], int):
            aliased[("insertions", "steps", *key[1:])] = line
    return aliased


def check_task(spec: TaskSpec, lines: dict[PathKey, int] | None = None) -> None:
    """Checks that need the whole tree; raise :class:`SpecError` at the first failure."""
    lines = lines or {}

    def fail(loc: PathKey, message: str) -> None:
        raise SpecError(format_path(loc), message, line_of(loc, lines))

    index: dict[str, int] = {}
    al_names: dict[str, PathKey] = {}
    for i, f in enumerate(spec.frames):
        if f.name in index:
            fail(("frames", i, "name"), f"duplicate frame name {f.name!r}")
        index[f.name] = i
        if f.al_name in al_names:
            fail(("frames", i, "al_name"), f"AL name {f.al_name!r} is already used")
        al_names[f.al_name] = ("frames", i, "al_name")
    if spec.manipulator is not None:
        for loc, name in (
            (("manipulator", "al_name"), spec.manipulator.al_name),
            (("manipulator", "park", "al_name"), spec.manipulator.park.al_name),
        ):
            if name in al_names:
                fail(loc, f"AL name {name!r} is already used by a frame")
            al_names[name] = loc
    # A reference (insertion.pin, --from) may be a frame name or an AL name; one spelling must
    # never mean two frames (AL names fold case, so the comparison does too).
    for i, f in enumerate(spec.frames):
        owner = al_names.get(f.name.upper())
        if owner is not None and owner != ("frames", i, "al_name"):
            fail(
                ("frames", i, "name"),
                f"frame name {f.name!r} is the AL name of {format_path(owner)}; "
                "a name may not refer to two frames",
            )

    for i, f in enumerate(spec.frames):
        if f.parent != WORLD and f.parent not in index:
            fail(("frames", i, "parent"), f"unknown parent {f.parent!r}")
    for i, f in enumerate(spec.frames):
        seen = {f.name}
        node = f
        while node.parent != WORLD:
            if node.parent in seen:
                fail(("frames", i, "parent"), f"frame {f.name!r} is in a cycle of parents")
            seen.add(node.parent)
            node = spec.frames[index[node.parent]]

    for i, f in enumerate(spec.frames):
        if f.shape is not None and f.shape.type == "hole":
            target = index.get(f.shape.surface)
            if target is None:
                fail(("frames", i, "shape", "surface"), f"unknown surface {f.shape.surface!r}")
            else:
                surface_shape = spec.frames[target].shape
                if surface_shape is None or surface_shape.type != "surface":
                    fail(("frames", i, "shape", "surface"), f"{f.shape.surface!r} is not a surface")
                _check_hole_surface(spec, i, target, fail)
        if f.uncertainty is not None:
            _check_feasible(f.uncertainty, ("frames", i, "uncertainty"), fail)
    if spec.manipulator is not None and spec.manipulator.hand_error is not None:
        _check_feasible(spec.manipulator.hand_error, ("manipulator", "hand_error"), fail)

    by_any = {f.name: f for f in spec.frames} | {f.al_name: f for f in spec.frames}
    for where, ins in _insertion_locations(spec):
        for field, want in (("pin", "pin"), ("hole", "hole"), ("start_hole", "hole")):
            ref = getattr(ins, field)
            if ref is None:
                continue
            frame = by_any.get(ref) or by_any.get(ref.upper())
            if frame is None:
                fail((*where, field), f"unknown frame {ref!r}")
            elif frame.shape is None or frame.shape.type != want:
                fail((*where, field), f"{ref!r} is not a {want}")
        _check_fit(ins, by_any, fail, where)
        _check_depths(ins, by_any, fail, where)
    for where, ins in _insertion_locations(spec):
        _check_start_hole(spec, ins, fail, where)

    check_contacts(spec, fail)  # contacts section: features exist, pairs and parents make sense
    _check_holes_fit(spec, fail)
    _check_outlines_fit(spec, fail)
    _check_solids_apart(spec, fail)


def _check_hole_surface(spec: TaskSpec, hole: int, surface: int, fail: Any) -> None:
    """Fail if a hole names a surface of another part (it is drilled into its own part's face).

    The tapping place and the search are measured on the named face, the replay drills the hole
    into its own part: a hole on another part's face was planned on the wrong solid.
    """
    graph = AttributeGraph(spec)
    names = spec.frames[hole].name, spec.frames[surface].name
    owners = graph.owner(names[0]), graph.owner(names[1])
    if owners[0] != owners[1]:
        fail(
            ("frames", hole, "shape", "surface"),
            f"hole {names[0]!r} belongs to {owners[0]!r} but surface {names[1]!r} to "
            f"{owners[1]!r}: a hole is drilled into a face of its own part",
        )


def _check_depths(
    ins: InsertionSpec, frames: dict[str, FrameSpec], fail: Any, where: PathKey
) -> None:
    """Fail if ``d_f`` is deeper than the target hole, or ``d_s`` not shallower than ``d_f``.

    A pin cannot be pushed deeper than its hole's bottom (the planner read "hand cannot grasp"
    into it), and the success test tells a seated pin from a miss by d_f − d_s (a negative
    limit otherwise). ``d_f`` given or derived (:func:`~synth.models.insertion.derived_d_f`):
    a d_s past the derived depth was planned, and every candidate refused as a tap that could
    not narrow Δz.
    """
    target = frames.get(ins.hole) or frames.get(ins.hole.upper())
    shape = None if target is None else target.shape
    if (
        ins.d_f is not None
        and isinstance(shape, HoleShape)
        and ins.d_f > shape.depth * (1.0 + 1e-9)
    ):
        fail(
            (*where, "d_f"),
            f"d_f = {100 * ins.d_f:.4g} cm is deeper than hole {ins.hole} "
            f"({100 * shape.depth:.4g} cm deep)",
        )
    d_f, derived = ins.d_f, ""
    pin_frame = frames.get(ins.pin) or frames.get(ins.pin.upper())
    pin_shape = None if pin_frame is None else pin_frame.shape
    if d_f is None and isinstance(shape, HoleShape) and isinstance(pin_shape, PinShape):
        d_f, derived = derived_d_f(pin_shape, shape), ", derived (the task gives none)"
    if d_f is not None and ins.d_s is not None and ins.d_s >= d_f:
        fail(
            (*where, "d_s"),
            f"d_s = {100 * ins.d_s:.4g} cm must be less than d_f = {100 * d_f:.4g} cm{derived}: "
            "the pin would start into the hole before it is seated",
        )


def _check_start_hole(spec: TaskSpec, ins: InsertionSpec, fail: Any, where: PathKey) -> None:
    """Fail if the pin does not stand in its ``start_hole``: on its axis, tip inside it.

    The planner pulls the pin out along the start hole's axis; one the pin is not in was
    accepted and ignored.
    """
    if ins.start_hole is None:
        return
    graph = AttributeGraph(spec)
    try:
        pin_name, hole_name = graph.resolve(ins.pin), graph.resolve(ins.start_hole)
    except FrameLookupError:
        return  # an unknown name is refused where it is checked
    hole = graph.nodes[hole_name].shape
    if not isinstance(hole, HoleShape):
        return
    if graph.resolve(ins.hole) == hole_name:
        fail(
            (*where, "hole"),
            f"pin {graph.al_names[pin_name]} already stands in {graph.al_names[hole_name]} "
            "(its start_hole): name the hole it goes into",
        )
    tip = graph.relative(hole_name, pin_name)
    lateral = float(np.hypot(*tip.translation[:2]))
    depth = -float(tip.translation[2])
    pin = graph.nodes[pin_name].shape
    # the pin's axis can stray from the hole's by the radial clearance, no more
    play = (hole.diameter - pin.diameter) / 2 if isinstance(pin, PinShape) else hole.diameter / 2
    wrong = []
    if lateral > max(play, 0.0) + 1e-6:
        wrong.append(
            f"its axis {100 * lateral:.3g} cm from the hole's, where the radial clearance "
            f"allows {100 * max(play, 0.0):.3g} cm"
        )
    if depth < -1e-6:
        wrong.append(f"tip {100 * -depth:.3g} cm above its mouth")
    elif depth > hole.depth + 1e-6:
        wrong.append(f"tip {100 * depth:.3g} cm deep in a hole {100 * hole.depth:.3g} cm deep")
    if wrong:
        index = next(i for i, f in enumerate(spec.frames) if f.name == pin_name)
        parent = spec.frames[index].parent
        fail(
            (*where, "start_hole"),
            f"pin {graph.al_names[pin_name]} does not stand in {graph.al_names[hole_name]} "
            f"({'; '.join(wrong)}); start_hole names the hole the pin is taken out of: name "
            f"the hole it stands in, or place it in this one (frames[{index}], its pose "
            f"against {parent})",
        )


def _check_outlines_fit(spec: TaskSpec, fail: Any) -> None:
    """Fail if a surface of a box part is not on one of its faces, or reaches beyond it.

    A surface is a face of its part: the pin taps it and the hole is drilled into it, and the
    replay's solid is the box. One off the box's faces (0.3 cm inside it, or tilted on it) was
    planned on a plane that is not there; an outline wider than the face put the tapping place
    in the air. Within :data:`_FACE_DISTANCE` and :data:`_FACE_ANGLE` a surface is on a face (a
    task in inches meets one in centimetres); surfaces of other shapes are not checked.
    """
    graph = AttributeGraph(spec)
    for i, f in enumerate(spec.frames):
        shape = f.shape
        if shape is None or shape.type != "surface":
            continue
        owner = graph.owner(f.name)
        box = graph.nodes[owner].shape if owner != WORLD else None
        if box is None or box.type != "box":
            continue
        local = graph.relative(owner, f.name)
        normal, origin = local.rotation[:, 2], local.translation
        faces = [g for g in box_features(box.size).values() if isinstance(g, Face)]
        face = max(faces, key=lambda g: float(g.normal @ normal))
        turned = math.acos(min(1.0, float(face.normal @ normal)))
        off = float(face.normal @ (origin - face.point))
        if turned > _FACE_ANGLE or abs(off) > _FACE_DISTANCE:
            side = "outside" if off > 0 else "inside"
            how = [f"{100 * abs(off):.4g} cm {side}"] if abs(off) > _FACE_DISTANCE else []
            how += [f"turned {math.degrees(turned):.3g}° from"] if turned > _FACE_ANGLE else []
            fail(
                ("frames", i, "pose"),
                f"surface {f.name!r} is not on a face of box {owner!r}: it is "
                f"{' and '.join(how)} the box's {face.name} face; a surface is a face of its "
                "part, where the pin taps and the hole is drilled",
            )
            continue
        edges = face.inward_edge_normals()
        for k, (x, y) in enumerate(shape.outline):
            corner = local.act(np.array([x, y, 0.0]))
            if any(float((corner - q) @ m) < -_FACE_DISTANCE for m, q in edges):
                size = " × ".join(f"{100 * v:.4g}" for v in box.size)
                fail(
                    ("frames", i, "shape", "outline", k),
                    f"outline vertex {k + 1} of {f.name!r} lies outside face {face.name} of box "
                    f"{owner!r} ({size} cm)",
                )


def _check_solids_apart(spec: TaskSpec, fail: Any) -> None:
    """Fail if two box parts, or a box part and the table, overlap at their nominal places.

    A rack standing inside a plate, or a plate 3 cm under the table top, was accepted: the
    replay's solids then overlap from the start (the pin's tip inside the plate), and a plan
    was "proven" in a workcell that cannot exist. Boxes that touch (a part on another, on the
    table) are apart; one inside its own ancestor's box is left to the task (a boss on a plate).
    Penetration is measured by Coal, beyond :data:`_FACE_DISTANCE`.
    """
    graph = AttributeGraph(spec)
    boxes: list[tuple[int, str, coal.Box, pin.SE3]] = []
    for i, f in enumerate(spec.frames):
        if f.shape is None or f.shape.type != "box":
            continue
        size = np.array(f.shape.size, dtype=float)
        centre = graph.world_from(f.name) * pin.SE3(np.eye(3), np.array([0.0, 0.0, size[2] / 2]))
        boxes.append((i, f.name, coal.Box(*size), centre))
    request, result = coal.DistanceRequest(), coal.DistanceResult()
    for i, name, box, centre in boxes:
        lowest = z_range(box, centre)[0]
        if lowest < -_FACE_DISTANCE:
            fail(
                ("frames", i, "pose"),
                f"box {name!r} reaches {100 * -lowest:.4g} cm under the table top (z = 0)",
            )
            continue
        for j, other, other_box, other_centre in boxes:
            if j <= i or other in graph.ancestors(name) or name in graph.ancestors(other):
                continue
            result.clear()
            depth = coal.distance(box, centre, other_box, other_centre, request, result)
            if depth < -_FACE_DISTANCE:
                fail(
                    ("frames", j, "pose"),
                    f"box {other!r} overlaps box {name!r} (by {100 * -depth:.4g} cm) at their "
                    "nominal places",
                )


def _check_holes_fit(spec: TaskSpec, fail: Any) -> None:
    """Fail if a hole drilled into a box's top face does not fit on that face, or in the box.

    The replay drills it with :func:`synth.models.meshes.box_with_holes`; its rule
    (:func:`~synth.models.meshes.hole_problem`: the mouth, of radius diameter/2 +
    chamfer_width, strictly inside the face) is checked here at the nominal pose. Holes
    elsewhere are left to the workcell, which names them. A hole in no part (no frame above
    it has a box shape) is refused: there is nothing to drill it into (the planner crashed on
    one, looking for the part's floor).
    """
    graph = AttributeGraph(spec)
    for i, f in enumerate(spec.frames):
        shape = f.shape
        if shape is None or shape.type != "hole":
            continue
        owner = graph.owner(f.name)
        if owner == WORLD:
            fail(
                ("frames", i, "parent"),
                f"hole {f.name!r} is in no part: no frame from {f.parent!r} up to the world "
                "has a box shape to drill it into",
            )
        box = graph.nodes[owner].shape
        if box is None or box.type != "box":
            continue
        local = graph.relative(owner, f.name)
        x, y, z = (round(float(v), 12) for v in local.translation)  # as the workcell does
        if local.rotation[2, 2] < 1.0 - _ON_FACE or abs(z - box.size[2]) > _ON_FACE:
            continue
        if shape.depth > box.size[2] + _ON_FACE:  # the pin's seat (d_f) would be below the box
            fail(
                ("frames", i, "shape", "depth"),
                f"hole {f.name!r} is {100 * shape.depth:.4g} cm deep in box {owner!r}, which is "
                f"{100 * box.size[2]:.4g} cm tall: a hole cannot be deeper than its box (a "
                "through hole's depth is the box's height)",
            )
        hole = (x, y, shape.diameter, shape.depth, shape.chamfer_width)
        problem = hole_problem(box.size, hole)
        if problem is not None:
            fail(("frames", i, "shape"), f"hole {f.name!r} does not fit box {owner!r}: {problem}")


_ON_FACE = 1e-6
"""[m], [rad]: how exactly a hole must sit on its box's top face to be checked against it (the
workcell's placement tolerance)."""

_FACE_DISTANCE = 1e-4
"""[m] How far from its box's face a surface may be declared: 0.1 mm, far below any position
tolerance a task gives, and above the rounding of sizes written in another unit."""

_FACE_ANGLE = 1e-3
"""[rad] How far a surface's normal may turn from its face's (0.057°)."""


def _insertion_locations(spec: TaskSpec) -> list[tuple[PathKey, InsertionSpec]]:
    """Each insertion with its place in the file: ``insertion`` or ``insertions.steps[i]``."""
    if spec.insertions is not None:
        return [(("insertions", "steps", i), s) for i, s in enumerate(spec.insertions.steps)]
    return [] if spec.insertion is None else [(("insertion",), spec.insertion)]


def _check_fit(
    ins: InsertionSpec, frames: dict[str, FrameSpec], fail: Any, where: PathKey = ("insertion",)
) -> None:
    """Fail if the insertion's pin is not thinner than its target (or start) hole."""

    def shape(ref: str | None) -> tuple[str, Any] | None:
        frame = None if ref is None else frames.get(ref) or frames.get(ref.upper())
        return None if frame is None else (frame.al_name, frame.shape)

    pin_ = shape(ins.pin)
    if pin_ is None:
        return
    for field in ("hole", "start_hole"):
        found = shape(getattr(ins, field))
        if found is None:
            continue
        problem = fit_problem(pin_[0], pin_[1].diameter, found[0], found[1].diameter)
        if problem is not None:
            fail((*where, field), problem)


def _check_feasible(unc: Uncertainty, loc: PathKey, fail: Any) -> None:
    """Fail if the block's bounds and coupled constraints admit no parameter vector (LP)."""
    if not unc.constraints:
        return
    bounds = [(b.lo, b.hi) for b in unc.bounds().values()]
    rows, rhs = unc.constraint_rows()
    res = linprog(
        np.zeros(len(bounds)),
        A_ub=np.array(rows),
        b_ub=np.array(rhs),
        bounds=bounds,
        method="highs",
    )
    if res.status == 2:
        fail((*loc, "constraints"), "the constraints and bounds admit no error values (infeasible)")
    if res.status != 0:
        fail((*loc, "constraints"), f"could not check the constraints: {res.message}")


def _first_error(errors: list[Any]) -> Any:
    """The error to report: the first, unless it is a missing field beside an unknown one.

    A mapping with a misspelt key gives pydantic's "<the required key> missing" first; the key
    the engineer wrote is the one to name (a misspelt field is the usual cause).
    """
    first = errors[0]
    if first.get("type") != "missing":
        return first
    parent = tuple(first.get("loc", ()))[:-1]
    for err in errors[1:]:
        if err.get("type") == "extra_forbidden" and tuple(err.get("loc", ()))[:-1] == parent:
            return err
    return first


def _message(err: Any) -> str:
    msg = str(err.get("msg", "invalid value"))
    for prefix in ("Value error, ", "Assertion failed, "):
        if msg.startswith(prefix):
            msg = msg[len(prefix) :]
    if err.get("type") == "missing":
        loc = err.get("loc", ())
        if loc and isinstance(loc[-1], int):  # a fixed-length list (x, y, z) ended early
            given = loc[-1]
            plural = "s" if given != 1 else ""
            return f"the list has {given} value{plural}; value {given + 1} is required too"
        return "this field is required"
    if err.get("type") == "extra_forbidden":
        return "unknown field"
    return msg


def _strip_union_tags(loc: tuple[Any, ...]) -> PathKey:
    # Pydantic puts the discriminator value ("hole", "pin", …) into the location of a tagged
    # union member and wraps BeforeValidator chains in "function-before[...]"; neither is a
    # field the user wrote.
    out: list[str | int] = []
    for part in loc:
        if (
            isinstance(part, str)
            and ("[" in part or part in ("box", "pin", "hole", "surface", "fixture"))
            and out
            and out[-1] == "shape"
        ):
            continue
        if isinstance(part, str) and part.startswith("function-"):
            continue
        out.append(part)
    return tuple(out)


__all__ = ["PARAMS", "check_task", "format_path", "load_task", "parse_task", "validate_task"]
