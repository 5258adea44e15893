"""Named features of object models — faces, edges and corners — and the checks on contacts.

Seed A.1 (L2946, L3068, L3112) names features of the box and the fixture (``bxbtm`` the box
bottom, ``be9`` a box edge, ``bfl.sb`` the fixture floor, ``bfls2`` a fixture side). Here the
features of a ``box`` and a ``fixture`` are derived from their size and named systematically:

* faces of a box: ``xpos``, ``xneg``, ``ypos``, ``yneg`` (the sides whose outward normal is
  ±x̂, ±ŷ of the box frame), ``top`` (+ẑ) and ``bottom`` (−ẑ);
* faces of a fixture (an open-topped box, origin at the centre of the inside floor): ``floor``
  (normal +ẑ), the inner walls ``xpos``, ``xneg``, ``ypos``, ``yneg`` (named by where they stand:
  ``xpos`` is the wall at x = +inside_x/2, its normal −x̂ points into the cavity) and the outer
  underside ``bottom`` (−ẑ);
* an edge is named by its two faces and a corner by its three, joined with ``_`` in any order:
  ``xneg_yneg`` is the vertical box edge at (−x, −y) (the seed's ``be9``), ``xpos_ypos_bottom``
  a bottom corner. Fixture edges and corners are concave (inside the cavity).

A frame whose shape is a ``surface`` is a face by itself: the plane z = 0 of that frame, outward
normal +ẑ, bounded by its outline.

Every normal points out of the material, into free space [unit]; points are in the owning
object's frame [m]. :func:`check_contacts` is the loader's whole-tree check of a task's
``contacts`` section; :func:`contact_groups` says which objects the contacts locate.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from synth.exceptions import FrameLookupError
from synth.models.contacts import ContactSpec
from synth.models.graph import AttributeGraph
from synth.models.spec import WORLD, TaskSpec

LOCATABLE_SHAPES = frozenset({"box", "fixture"})
"""Shapes with named features and vertices: objects that can be located by contacts."""

BOX_FACES: tuple[str, ...] = ("xpos", "xneg", "ypos", "yneg", "top", "bottom")
FIXTURE_FACES: tuple[str, ...] = ("floor", "xpos", "xneg", "ypos", "yneg", "bottom")

_EPS = 1e-12  # [m] coincidence tolerance when matching vertices to faces


@dataclass(frozen=True, eq=False)
class Face:
    """A planar face: outward unit ``normal``, a ``point`` on it [m], convex ``outline`` [m].

    ``outline`` is (k, 3), counter-clockwise seen from the side the normal points to.
    """

    name: str
    normal: np.ndarray
    point: np.ndarray
    outline: np.ndarray

    kind = "face"

    def transformed(self, owner_from_frame: pin.SE3) -> Face:
        """The face expressed in another frame: ``n ↦ R n``, ``p ↦ R p + t``."""
        r, t = owner_from_frame.rotation, owner_from_frame.translation
        return Face(self.name, r @ self.normal, r @ self.point + t, self.outline @ r.T + t)

    def inward_edge_normals(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """(m_k, q_k) per outline edge k: inward in-plane unit normal and a point on the edge.

        A point x of the plane is inside the face iff m_k·(x − q_k) ≥ 0 for every k.
        """
        centre = self.outline.mean(axis=0)
        out = []
        for q0, q1 in zip(self.outline, np.roll(self.outline, -1, axis=0), strict=True):
            m = np.cross(self.normal, q1 - q0)
            m /= np.linalg.norm(m)
            if m @ (centre - q0) < 0:
                m = -m
            out.append((m, q0.copy()))
        return out

    def is_convex(self) -> bool:
        """True when every outline vertex lies inside every edge's half-plane."""
        return all(np.all((self.outline - q) @ m >= -1e-12) for m, q in self.inward_edge_normals())


@dataclass(frozen=True, eq=False)
class Edge:
    """A straight edge from ``start`` to ``end`` [m] between two faces with outward ``normals``.

    ``convex`` edges stick out of the material (a box edge); concave ones are creases of a
    cavity (a fixture's inside corner).
    """

    name: str
    start: np.ndarray
    end: np.ndarray
    normals: tuple[np.ndarray, np.ndarray]
    convex: bool

    kind = "edge"


@dataclass(frozen=True, eq=False)
class Corner:
    """A vertex ``point`` [m] where three faces with outward ``normals`` meet."""

    name: str
    point: np.ndarray
    normals: tuple[np.ndarray, np.ndarray, np.ndarray]
    convex: bool

    kind = "corner"


Feature = Face | Edge | Corner


@dataclass(frozen=True, eq=False)
class FeatureRef:
    """A resolved feature reference: the object owning it and the feature in that object's frame."""

    ref: str
    owner: str
    frame: str
    feature: Feature


def _box_vertices(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    return np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )


def _faces_of_box(
    lo: np.ndarray, hi: np.ndarray, names: dict[tuple[int, int], str], flip: bool
) -> dict[str, Face]:
    """Faces of the axis-aligned box [lo, hi] [m], named by ``names[(axis, ±1)]``.

    ``flip`` turns the normals inwards (a cavity's walls seen from the material around it).
    """
    verts = _box_vertices(lo, hi)
    faces = {}
    for (axis, sign), name in names.items():
        coord = hi[axis] if sign > 0 else lo[axis]
        on = verts[np.abs(verts[:, axis] - coord) < _EPS]
        normal = np.zeros(3)
        normal[axis] = -sign if flip else sign
        centre = on.mean(axis=0)
        # Order the four vertices counter-clockwise about the normal.
        u = np.zeros(3)
        u[(axis + 1) % 3] = 1.0
        v = np.cross(normal, u)
        order = np.argsort(np.arctan2((on - centre) @ v, (on - centre) @ u))
        faces[name] = Face(name, normal, centre.copy(), on[order].copy())
    return faces


def _edges_and_corners(
    faces: dict[str, Face], order: Sequence[str], convex: bool
) -> dict[str, Feature]:
    """Edges (two faces sharing two outline vertices) and corners (three sharing one)."""
    out: dict[str, Feature] = {}
    for n in (2, 3):
        for combo in itertools.combinations(order, n):
            if not all(c in faces for c in combo):
                continue
            shared = faces[combo[0]].outline
            for c in combo[1:]:
                other = faces[c].outline
                keep = [p for p in shared if np.min(np.linalg.norm(other - p, axis=1)) < _EPS]
                shared = np.array(keep).reshape(-1, 3)
            shared = shared[np.lexsort(shared.T)]  # lowest z (then y, x) first
            normals = tuple(faces[c].normal for c in combo)
            name = "_".join(combo)
            if n == 2 and len(shared) == 2:
                out[name] = Edge(
                    name, shared[0].copy(), shared[1].copy(), (normals[0], normals[1]), convex
                )
            elif n == 3 and len(shared) == 1:
                out[name] = Corner(
                    name, shared[0].copy(), (normals[0], normals[1], normals[2]), convex
                )
    return out


def box_features(size: Sequence[float]) -> dict[str, Feature]:
    """Faces, edges and corners of a box of ``size`` (x, y, z) [m]; origin at the bottom centre."""
    sx, sy, sz = size
    lo, hi = np.array([-sx / 2, -sy / 2, 0.0]), np.array([sx / 2, sy / 2, sz])
    names = {
        (0, 1): "xpos",
        (0, -1): "xneg",
        (1, 1): "ypos",
        (1, -1): "yneg",
        (2, 1): "top",
        (2, -1): "bottom",
    }
    faces = _faces_of_box(lo, hi, names, flip=False)
    return {**faces, **_edges_and_corners(faces, BOX_FACES, convex=True)}


def fixture_features(inside: Sequence[float], wall: float, floor: float) -> dict[str, Feature]:
    """Features of an open-topped box (seed Figure A.1).

    Cavity ``inside`` (x, y, depth), ``wall`` and ``floor`` thicknesses [m]; origin at the centre
    of the inside floor, z up.
    """
    lx, ly, depth = inside
    lo, hi = np.array([-lx / 2, -ly / 2, 0.0]), np.array([lx / 2, ly / 2, depth])
    names = {(0, 1): "xpos", (0, -1): "xneg", (1, 1): "ypos", (1, -1): "yneg", (2, -1): "floor"}
    faces = _faces_of_box(lo, hi, names, flip=True)
    outer_lo = np.array([-lx / 2 - wall, -ly / 2 - wall, -floor])
    outer_hi = np.array([lx / 2 + wall, ly / 2 + wall, depth])
    faces |= _faces_of_box(outer_lo, outer_hi, {(2, -1): "bottom"}, flip=False)
    inner = {k: v for k, v in faces.items() if k != "bottom"}
    return {**faces, **_edges_and_corners(inner, FIXTURE_FACES, convex=False)}


def features_of(shape: Any) -> dict[str, Feature]:
    """Named features of a ``box`` or ``fixture`` shape, in its frame."""
    if shape.type == "box":
        return box_features(shape.size)
    if shape.type == "fixture":
        return fixture_features(shape.inside, shape.wall, shape.floor)
    raise ValueError(f"a {shape.type} has no named features")


def object_vertices(shape: Any) -> np.ndarray:
    """The 8 vertices (8, 3) [m] of the solid hull of a ``box`` or ``fixture``, in its frame."""
    if shape.type == "box":
        sx, sy, sz = shape.size
        return _box_vertices(np.array([-sx / 2, -sy / 2, 0.0]), np.array([sx / 2, sy / 2, sz]))
    if shape.type == "fixture":
        lx, ly, depth = shape.inside
        w, f = shape.wall, shape.floor
        return _box_vertices(
            np.array([-lx / 2 - w, -ly / 2 - w, -f]), np.array([lx / 2 + w, ly / 2 + w, depth])
        )
    raise ValueError(f"a {shape.type} has no vertices")


def surface_face(name: str, outline: Sequence[tuple[float, float]]) -> Face:
    """The face of a ``surface`` frame: plane z = 0, normal +ẑ, counter-clockwise outline [m]."""
    pts = np.array([[x, y, 0.0] for x, y in outline])
    area2 = float(np.sum(pts[:, 0] * np.roll(pts[:, 1], -1) - np.roll(pts[:, 0], -1) * pts[:, 1]))
    if area2 < 0:
        pts = pts[::-1].copy()
    return Face(name, np.array([0.0, 0.0, 1.0]), np.zeros(3), pts)


def canonical_feature(name: str, order: Sequence[str]) -> str:
    """``yneg_xneg`` → ``xneg_yneg``: face names of an edge or corner in canonical order."""
    parts = name.split("_")
    if all(p in order for p in parts):
        return "_".join(sorted(parts, key=order.index))
    return name


def locating_owner(graph: AttributeGraph, frame: str) -> str:
    """The nearest ancestor of ``frame`` (or itself) with a box or fixture shape, else world."""
    for n in graph.ancestors(frame):
        if n != WORLD and graph.nodes[n].kind in LOCATABLE_SHAPES:
            return n
    return WORLD


class FeatureError(ValueError):
    """A feature reference that does not name a feature (message says why)."""


def resolve_feature(graph: AttributeGraph, ref: str) -> FeatureRef:
    """The feature named by ``ref`` (``frame.feature`` or a surface frame), in its owner's frame.

    Raises :class:`FeatureError` with a message listing what exists.
    """
    frame_name, _, feature_name = ref.partition(".")
    try:
        frame = graph.resolve(frame_name)
    except FrameLookupError:
        raise FeatureError(f"unknown frame {frame_name!r}") from None
    if frame == WORLD:
        raise FeatureError("the world frame has no features")
    shape = graph.nodes[frame].shape
    if feature_name:
        if shape is None or shape.type not in LOCATABLE_SHAPES:
            what = "no shape" if shape is None else f"a {shape.type} shape"
            raise FeatureError(
                f"{frame!r} has {what}; named features exist on box and fixture shapes"
            )
        features = features_of(shape)
        order = BOX_FACES if shape.type == "box" else FIXTURE_FACES
        key = canonical_feature(feature_name, order)
        if key not in features:
            faces = ", ".join(order)
            raise FeatureError(
                f"{frame!r} (a {shape.type}) has no feature {feature_name!r}; its faces are "
                f"{faces}, an edge joins two faces and a corner three with '_' (e.g. "
                f"{next(k for k in features if k.count('_') == 1)})"
            )
        return FeatureRef(ref, frame, frame, features[key])
    if shape is None or shape.type != "surface":
        raise FeatureError(
            f"{frame!r} is not a surface frame; name a feature of it as {frame_name}.FEATURE"
        )
    owner = locating_owner(graph, frame)
    if owner == WORLD:
        raise FeatureError(f"surface {frame!r} does not belong to a box or fixture")
    for link in graph.path(owner, frame).down:
        if link.uncertainty is not None and link.uncertainty.bounds():
            raise FeatureError(
                f"surface {frame!r} is not rigidly placed on {owner!r} (link {link.child!r} has "
                "an uncertainty block)"
            )
    face = surface_face(frame, shape.outline).transformed(graph.relative(owner, frame))
    return FeatureRef(ref, owner, frame, face)


def contact_groups(
    graph: AttributeGraph, contacts: Sequence[ContactSpec]
) -> dict[str, tuple[int, ...]]:
    """Located object → indices of the contacts that locate it (the owner of each ``a``).

    Assumes the contacts passed :func:`check_contacts`.
    """
    groups: dict[str, list[int]] = {}
    for i, c in enumerate(contacts):
        groups.setdefault(resolve_feature(graph, c.a).owner, []).append(i)
    return {k: tuple(v) for k, v in groups.items()}


Fail = Callable[[tuple[str | int, ...], str], object]
"""The loader's ``fail(path, message)``: raises :class:`~synth.exceptions.SpecError`."""


def check_contacts(spec: TaskSpec, fail: Fail) -> None:
    """The loader's checks of ``spec.contacts`` (call after the frame tree is known to be sound).

    Per contact: both features exist; ``b`` is a face; ``a`` is a face, a convex edge or a corner
    of a box or fixture; ``a`` and ``b`` belong to different objects; ``inside_of`` joins two
    faces, and ``b`` then has a convex outline. Per located object (the owner of ``a``): one
    object ``b`` belongs to, which is also its parent; a face–face contact to rest on (the
    first); a resting face whose normal is an axis of the object frame; no hand-written pose
    or uncertainty, since both are derived.
    """
    if not spec.contacts:
        return
    graph = AttributeGraph(spec)
    frame_index = {f.name: i for i, f in enumerate(spec.frames)}
    resolved: list[tuple[FeatureRef, FeatureRef]] = []
    for i, c in enumerate(spec.contacts):
        refs = []
        for side in ("a", "b"):
            try:
                refs.append(resolve_feature(graph, getattr(c, side)))
            except FeatureError as exc:
                fail(("contacts", i, side), str(exc))
        fa, fb = refs
        if fb.feature.kind != "face":
            fail(
                ("contacts", i, "b"),
                f"{c.b!r} is {_article(fb.feature.kind)}; the feature touched (b) must be a face",
            )
        if fa.feature.kind != "face" and c.kind == "inside_of":
            fail(
                ("contacts", i, "kind"),
                f"inside_of joins two faces, but {c.a!r} is "
                f"{_article(fa.feature.kind)}; use extent_irrelevant",
            )
        if isinstance(fa.feature, Edge | Corner) and not fa.feature.convex:
            fail(
                ("contacts", i, "a"),
                f"{c.a!r} is a concave {fa.feature.kind} of a fixture; "
                "only convex edges and corners can touch a face",
            )
        if fa.owner == fb.owner:
            fail(
                ("contacts", i, "b"), f"{c.a!r} and {c.b!r} belong to the same object {fa.owner!r}"
            )
        if c.kind == "inside_of":
            assert isinstance(fb.feature, Face)
            if not fb.feature.is_convex():
                fail(
                    ("contacts", i, "b"),
                    f"inside_of needs a convex face, but {c.b!r} has a non-convex outline",
                )
        resolved.append((fa, fb))

    groups = contact_groups(graph, spec.contacts)
    for obj, idx in groups.items():
        k = frame_index[obj]
        frame = spec.frames[k]
        first = idx[0]
        reference = resolved[first][1].owner
        for i in idx:
            if resolved[i][1].owner != reference:
                fail(
                    ("contacts", i, "b"),
                    f"{obj!r} already rests against {reference!r} "
                    f"(contacts[{first}]); an object is located against one object only",
                )
        rest = [i for i in idx if resolved[i][0].feature.kind == "face"]
        if not rest:
            fail(
                ("contacts", first, "a"),
                f"{obj!r} is located by contacts but none of them is "
                "face on face: say which face it rests on (e.g. its bottom on a floor)",
            )
        face = resolved[rest[0]][0].feature
        assert isinstance(face, Face)
        if np.max(np.abs(face.normal)) < 1.0 - 1e-9:
            fail(
                ("contacts", rest[0], "a"),
                f"the resting face {spec.contacts[rest[0]].a!r} "
                f"must have its normal along an axis of {obj!r}'s frame",
            )
        if frame.parent != reference:
            fail(
                ("frames", k, "parent"),
                f"{obj!r} is located by contacts against "
                f"{reference!r}, so its parent must be {reference!r}",
            )
        for field in ("pose", "uncertainty"):
            if field in frame.model_fields_set:
                fail(
                    ("frames", k, field),
                    f"the {field} of {obj!r} is derived from its "
                    f"contacts (contacts[{', '.join(map(str, idx))}]); remove it",
                )


def _article(kind: str) -> str:
    return f"an {kind}" if kind[0] in "aeiou" else f"a {kind}"


__all__ = [
    "BOX_FACES",
    "FIXTURE_FACES",
    "LOCATABLE_SHAPES",
    "Corner",
    "Edge",
    "Face",
    "Feature",
    "FeatureError",
    "FeatureRef",
    "box_features",
    "canonical_feature",
    "check_contacts",
    "contact_groups",
    "features_of",
    "fixture_features",
    "locating_owner",
    "object_vertices",
    "resolve_feature",
    "surface_face",
]
