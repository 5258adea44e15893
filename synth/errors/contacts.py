"""Contact relations as constraints on an object's free parameters (seed A.1, L2938–3156).

An object resting with face ``a`` on face ``b`` of a reference object keeps four degrees of
freedom, the seed's ``PV = [X, Y, Z]`` and ``W`` (L3024–3025): its origin ``P`` in the
reference frame [m] and the rotation ``w`` [rad] about ``n̂_a``, the outward normal of its
resting face::

    R(w) = R_align · rot(n̂_a, w)          (the seed's R = NILROTN · ROTN(−ẐHAT, W))

``R_align`` is the fixed rotation taking ``n̂_a`` onto ``−n̂_b`` (the identity in A.1, where the
box bottom's normal −ẑ already opposes the floor's +ẑ). Every contact becomes rows of the form

    g·P + h·R(w)·c  ≤  rhs      or      … = rhs                                  (1)

with ``h`` a unit direction and ``c`` a vector in the object frame — exactly the seed's listing
``XHAT·R·5.85·VECTOR(−.760, −.649, 0) ≤ 4.000 − XHAT·PV`` (L3126, here g = h = x̂, c the box
corner, rhs = 4 cm). By Rodrigues' formula each row is linear in (P, cos w, sin w):

    h·R(w)·c = k₀ + k_c cos w + k_s sin w,   h' = R_alignᵀh,
    k₀ = (h'·n̂_a)(n̂_a·c),  k_c = h'·c − k₀,  k_s = h'·(n̂_a × c)                (2)

Rows per contact kind:

* resting face on face: ``n̂_b·(P + R p_a) = n̂_b·p_b`` (the seed's ``0 = .000 − ZHAT·PV``, L3023);
* ``inside_of``: every vertex v of the object inside every edge k of b's outline,
  ``m_k·(P + R v) ≥ m_k·q_k`` (in-plane inward normal m_k) — the 16 rows of L3007–3022;
* edge on face (``extent_irrelevant``): both end points on the plane (equalities, L3139–3141);
  the face normal inside the edge's normal cone, ``n̂_b·R·d ≤ −cos β`` with d the unit bisector
  of the edge's face normals and β half their angle (L3072: ``−XHAT·R·(−.707, −.707, 0) ≤
  −.707``); every vertex on the free side of the plane;
* corner on face: the vertex on the plane, every vertex on the free side;
* a further face on face: plane coincidence, ``R n̂_a = −n̂_b`` (three rows linear in cos w, sin
  w) and the free side.

Rows that are the same function of (P, w) are kept once (a box's top corners repeat its bottom
ones). :func:`build_contact_problem` builds the rows; :mod:`synth.errors.locate` bounds them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from synth.exceptions import EstimationError
from synth.models.contacts import ContactSpec
from synth.models.features import (
    Corner,
    Edge,
    Face,
    FeatureError,
    FeatureRef,
    object_vertices,
    resolve_feature,
)
from synth.models.graph import AttributeGraph


@dataclass(frozen=True, eq=False)
class ContactConstraint:
    """One row ``g·P + h·R(w)·c ≤ rhs`` (or ``= rhs``) of Eqn (1).

    ``position`` g [-], ``direction`` h [-] (reference frame), ``vector`` c (object frame; [m]
    for a point, [-] for a direction), ``rhs`` [m] (or [-] when g = 0 and c is a direction).
    ``contact`` indexes the contacts passed to :func:`build_contact_problem`; ``role`` is
    ``rest``, ``inside``, ``touch``, ``cone``, ``align`` or ``clear`` (module docstring).
    """

    position: np.ndarray
    direction: np.ndarray
    vector: np.ndarray
    rhs: float
    equality: bool
    contact: int
    role: str


@dataclass(frozen=True, eq=False)
class ContactProblem:
    """The rows locating ``obj`` in the frame of ``reference``, and the parametrisation of R(w).

    ``axis`` is n̂_a (object frame), ``align`` is R_align; ``vertices`` (8, 3) [m] are the
    object's, ``length_scale`` [m] their largest distance from its origin (used to scale LPs).
    """

    obj: str
    reference: str
    contacts: tuple[ContactSpec, ...]
    indices: tuple[int, ...]
    rest_face: str
    axis: np.ndarray
    align: np.ndarray
    constraints: tuple[ContactConstraint, ...]
    vertices: np.ndarray
    length_scale: float

    def rotation(self, w: float) -> np.ndarray:
        """``R(w) = R_align · rot(n̂_a, w)``, the object's orientation in the reference frame."""
        return self.align @ pin.exp3(self.axis * w)

    def trig_form(self) -> TrigForm:
        """Every row as ``G P + k₀ + k_c cos w + k_s sin w (≤ | =) rhs`` (Eqn 2)."""
        n = self.axis
        rows = self.constraints
        g = np.array([c.position for c in rows]).reshape(len(rows), 3)
        h = np.array([self.align.T @ c.direction for c in rows]).reshape(len(rows), 3)
        vec = np.array([c.vector for c in rows]).reshape(len(rows), 3)
        k0 = (h @ n) * (vec @ n)
        kc = np.einsum("ij,ij->i", h, vec) - k0
        ks = np.einsum("ij,ij->i", h, np.cross(n, vec))
        rhs = np.array([c.rhs for c in rows], dtype=float)
        eq = np.array([c.equality for c in rows], dtype=bool)
        return TrigForm(g, k0, kc, ks, rhs, eq)


@dataclass(frozen=True, eq=False)
class TrigForm:
    """Rows ``G P + k₀ + k_c cos w + k_s sin w (≤ | =) rhs``; ``equality`` marks ``=`` rows."""

    position: np.ndarray  # (m, 3) [-]
    k0: np.ndarray  # (m,) [m] or [-]
    kc: np.ndarray  # (m,)
    ks: np.ndarray  # (m,)
    rhs: np.ndarray  # (m,)
    equality: np.ndarray  # (m,) bool

    def residual(self, position: np.ndarray, w: float) -> np.ndarray:
        """``G P + k₀ + k_c cos w + k_s sin w − rhs`` for one pose: ≤ 0 (or = 0) when satisfied."""
        return (
            self.position @ position
            + self.k0
            + self.kc * np.cos(w)
            + self.ks * np.sin(w)
            - self.rhs
        )


def alignment(normal_a: np.ndarray, normal_b: np.ndarray) -> np.ndarray:
    """The least rotation taking ``normal_a`` onto ``−normal_b`` (faces pressed together).

    Antiparallel normals (A.1's box bottom −ẑ on the floor +ẑ) give the identity; parallel ones
    a half turn about the object axis most perpendicular to ``normal_a``.
    """
    v, t = normal_a / np.linalg.norm(normal_a), -normal_b / np.linalg.norm(normal_b)
    c = float(np.clip(v @ t, -1.0, 1.0))
    if c > 1.0 - 1e-12:
        return np.eye(3)
    if c < -1.0 + 1e-12:
        e = np.zeros(3)
        e[int(np.argmin(np.abs(v)))] = 1.0
        axis = np.cross(v, e)
        return np.asarray(pin.exp3(axis / np.linalg.norm(axis) * np.pi))
    axis = np.cross(v, t)
    return np.asarray(pin.exp3(axis / np.linalg.norm(axis) * np.arccos(c)))


def build_contact_problem(
    graph: AttributeGraph,
    obj: str,
    contacts: Sequence[ContactSpec],
    indices: Sequence[int] | None = None,
) -> ContactProblem:
    """The constraint rows (Eqn 1) that ``contacts`` put on the pose of ``obj``.

    ``contacts`` are the contacts locating ``obj`` (their ``a`` features belong to it; the first
    face on face is the resting one); ``indices`` are their positions in the task's list, for
    messages. Raises :class:`EstimationError` if the contacts do not fit that pattern (the
    loader's :func:`synth.models.features.check_contacts` rejects such specs first).
    """
    idx = tuple(indices) if indices is not None else tuple(range(len(contacts)))
    where = ", ".join(f"contacts[{i}]" for i in idx)
    try:
        refs = [(resolve_feature(graph, c.a), resolve_feature(graph, c.b)) for c in contacts]
    except FeatureError as exc:
        raise EstimationError(f"{where}: {exc}") from None
    if not refs or any(fa.owner != obj for fa, _ in refs):
        raise EstimationError(
            f"{where}: every contact locating {obj!r} must name one of its features as a"
        )
    reference = refs[0][1].owner
    if any(fb.owner != reference for _, fb in refs):
        raise EstimationError(f"{where}: {obj!r} must be located against one object")
    rest = next(
        (
            k
            for k, (fa, fb) in enumerate(refs)
            if isinstance(fa.feature, Face) and isinstance(fb.feature, Face)
        ),
        None,
    )
    if rest is None:
        raise EstimationError(f"{where}: {obj!r} needs a face-on-face contact to rest on")
    face_a, face_b = refs[rest][0].feature, refs[rest][1].feature
    assert isinstance(face_a, Face) and isinstance(face_b, Face)
    shape = graph.nodes[obj].shape
    vertices = object_vertices(shape)
    rows: list[ContactConstraint] = []
    for k, (c, (fa, fb)) in enumerate(zip(contacts, refs, strict=True)):
        rows += _rows(k, c, fa, fb, vertices, is_rest=k == rest)
    problem = ContactProblem(
        obj=obj,
        reference=reference,
        contacts=tuple(contacts),
        indices=idx,
        rest_face=contacts[rest].a,
        axis=face_a.normal.copy(),
        align=alignment(face_a.normal, face_b.normal),
        constraints=tuple(rows),
        vertices=vertices,
        length_scale=float(np.max(np.linalg.norm(vertices, axis=1))),
    )
    return _deduplicated(problem)


def _rows(
    k: int,
    contact: ContactSpec,
    fa: FeatureRef,
    fb: FeatureRef,
    vertices: np.ndarray,
    *,
    is_rest: bool,
) -> list[ContactConstraint]:
    b = fb.feature
    assert isinstance(b, Face)
    n, level = b.normal, float(b.normal @ b.point)
    zero = np.zeros(3)
    rows: list[ContactConstraint] = []

    def on_plane(point: np.ndarray, role: str) -> None:  # n·(P + R p) = n·p_b
        rows.append(ContactConstraint(n, n, point.copy(), level, True, k, role))

    a = fa.feature
    if isinstance(a, Face):
        on_plane(a.point, "rest" if is_rest else "touch")
        if not is_rest:  # R n_a' = −n_b, componentwise
            for i in range(3):
                e = np.eye(3)[i]
                rows.append(
                    ContactConstraint(zero, e, a.normal.copy(), float(-n[i]), True, k, "align")
                )
    elif isinstance(a, Edge):
        on_plane(a.start, "touch")
        on_plane(a.end, "touch")
        d = a.normals[0] + a.normals[1]
        d /= np.linalg.norm(d)
        rows.append(ContactConstraint(zero, n, d, -float(d @ a.normals[0]), False, k, "cone"))
    elif isinstance(a, Corner):
        on_plane(a.point, "touch")
    if not is_rest:  # every vertex on the free side: −n·(P + R v) ≤ −n·p_b
        rows += [ContactConstraint(-n, -n, v.copy(), -level, False, k, "clear") for v in vertices]
    if contact.kind == "inside_of":
        for m, q in b.inward_edge_normals():  # m·(P + R v) ≥ m·q
            rows += [
                ContactConstraint(-m, -m, v.copy(), -float(m @ q), False, k, "inside")
                for v in vertices
            ]
    return rows


def _deduplicated(problem: ContactProblem) -> ContactProblem:
    """Drop rows that are the same function of (P, w) as an earlier row, and ``0 = 0`` rows."""
    form = problem.trig_form()
    scale = problem.length_scale
    keep: list[ContactConstraint] = []
    seen: set[tuple[object, ...]] = set()
    for i, row in enumerate(problem.constraints):
        coeffs = (*form.position[i], form.k0[i] / scale, form.kc[i] / scale, form.ks[i] / scale)
        if (
            row.equality
            and max(abs(x) for x in coeffs) < 1e-12
            and abs(form.rhs[i]) < 1e-12 * scale
        ):
            continue
        key = (
            *(round(float(x), 10) for x in coeffs),
            round(float(form.rhs[i]) / scale, 10),
            row.equality,
        )
        if key in seen:
            continue
        seen.add(key)
        keep.append(row)
    return ContactProblem(
        problem.obj,
        problem.reference,
        problem.contacts,
        problem.indices,
        problem.rest_face,
        problem.axis,
        problem.align,
        tuple(keep),
        problem.vertices,
        problem.length_scale,
    )


__all__ = [
    "ContactConstraint",
    "ContactProblem",
    "TrigForm",
    "alignment",
    "build_contact_problem",
]
