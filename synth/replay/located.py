"""True poses of objects located by contacts, sampled from the contacts themselves.

A task may say how an object rests instead of where it is (``docs/contacts.md``; seed A.1,
L2938–3156: "our box" in a fixture). The planner bounds such an object by linear programming
(:mod:`synth.errors.locate`); the referee must not take that estimate for the truth, or a wrong
estimate could never fail a replay (design card: "the replay is the referee"). Here the true
pose of a located object O in the frame of the object B it touches — its parent, whose own
pose is sampled with its own errors like any frame's — is drawn from the contacts alone, with
no call into :mod:`synth.errors`.

**Free degrees of freedom.** O rests with face a on face b of B (the first face-on-face
contact, as in the seed's ``R = NILROTN·ROTN(−ẐHAT, W)``, L3024), so its orientation is

    R(w) = R₀ · rot(n̂_a, w),   R₀ n̂_a = −n̂_b,

R₀ any fixed rotation doing so (Pinocchio's ``Quaternion.FromTwoVectors``): w runs over the
whole circle, so the choice does not matter. With Rodrigues' formula and K = [n̂_a]×,
R(w) = R₀(I + K²) − cos w · R₀K² + sin w · R₀K. Every point-on-plane condition of the contacts
— the faces on faces, both ends of an edge on a face, a corner on a face — is linear in the
origin P at fixed w:

    n̂ᵢ·(P + R(w) pᵢ) = ℓᵢ,   stacked:  G P = r(w),   rᵢ(w) = ℓᵢ − n̂ᵢ·R(w) pᵢ.

A combination λ with λᵀG = 0 is a condition on w alone, λᵀr(w) = 0 (the final problem of A.1:
edges against the walls x = +4 and x = −4 cm fix the box's width across them, hence w); a
second face on face adds R(w) n̂_a′ = −n̂_b′. Each is a sinusoid k₀ + k_c cos w + k_s sin w = 0
with the closed-form roots w = atan2(k_s, k_c) ± acos(−k₀/ρ), ρ = hypot(k_c, k_s); w is then
one of the roots that satisfy every other condition. P = G⁺r(w) + N t, N an orthonormal basis
of G's null space (the directions no contact fixes), t = NᵀP.

**Proposal.** w uniform on (−π, π] (or one of its roots, each alike), t uniform on the box in
which an ``inside_of`` contact keeps the centroid c̄ of O's vertices: every vertex projects
inside b's convex outline, so does c̄, and N ⊥ n̂_b, so ``Nᵀ(P + R c̄) ∈ [min_q Nᵀq, max_q Nᵀq]``
over the outline's vertices q, i.e. ``t ∈ [min_q Nᵀq, max_q Nᵀq] − NᵀR(w)c̄``. The box holds
every feasible pose and its size does not depend on w, so the accepted draws are uniform in
(w, t) on the contact set. An object with a free direction and no ``inside_of`` contact is
unbounded (an error, as :mod:`synth.errors.locate` also reports).

**Acceptance** — the exact constraints of each kind (``docs/contacts.md``, "Kinds"): every
vertex v of O on the free side of every plane it touches, ``n̂_b·(P + R v) ≥ ℓ_b``; for
``inside_of``, every vertex inside every edge k of b's outline, ``m_k·(P + R v − q_k) ≥ 0``
(m_k the inward in-plane normal). The slack is 10⁻⁹ m; the equalities hold by construction.

**Bounded and reproducible.** Candidates come in batches of 512, 1 024, … (at most 65 536) from
the caller's generator and the first accepted one is taken, so a pose depends only on the
generator's state. After 2²² candidates without one (an acceptance rate below 2.4·10⁻⁷: the
contacts leave a set too thin to sample) :class:`~synth.exceptions.SpecError` says so.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.exceptions import SpecError
from synth.models.contacts import ContactSpec
from synth.models.features import (
    Corner,
    Edge,
    Face,
    FeatureRef,
    contact_groups,
    object_vertices,
    resolve_feature,
)
from synth.models.graph import AttributeGraph

__all__ = ["MAX_CANDIDATES", "ContactPlacement", "located_objects"]

SLACK = 1e-9
"""[m] (or [1] for unit vectors) slack of the inequality and root checks."""
MAX_CANDIDATES = 1 << 22
"""Candidates drawn for one pose before the contacts are declared too thin to sample."""
_FIRST_BATCH = 512
_MAX_BATCH = 65_536

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class _Sinusoid:
    """``k0 + kc cos w + ks sin w`` (a condition ``= 0`` on w alone)."""

    k0: float
    kc: float
    ks: float

    def __call__(self, w: float) -> float:
        return self.k0 + self.kc * math.cos(w) + self.ks * math.sin(w)

    @property
    def trivial(self) -> bool:
        return max(abs(self.k0), abs(self.kc), abs(self.ks)) <= SLACK

    def roots(self) -> list[float]:
        """Its zeros on (−π, π] in closed form (none, one when tangent, or two)."""
        rho = math.hypot(self.kc, self.ks)
        if rho <= SLACK:
            return []
        c = -self.k0 / rho
        if abs(c) > 1.0 + 1e-12:
            return []
        phi, half = math.atan2(self.ks, self.kc), math.acos(min(max(c, -1.0), 1.0))
        out: list[float] = []
        for w in (phi - half, phi + half):
            w = math.remainder(w, 2.0 * math.pi)
            if all(abs(math.remainder(w - u, 2.0 * math.pi)) > 1e-12 for u in out):
                out.append(w)
        return out


class ContactPlacement:
    """The pose of one located object in its reference's frame, drawn from its contacts.

    ``contacts`` are ``(index, contact)`` pairs, the index being the contact's place in the
    task (for messages). Raises :class:`SpecError` when the contacts admit no pose or leave it
    unbounded. See the module docstring for the algorithm.
    """

    def __init__(
        self, graph: AttributeGraph, obj: str, contacts: tuple[tuple[int, ContactSpec], ...]
    ) -> None:
        self.obj = obj
        self.indices = tuple(i for i, _ in contacts)
        self.where = ", ".join(f"contacts[{i}]" for i in self.indices)
        refs = [(resolve_feature(graph, c.a), resolve_feature(graph, c.b), c) for _, c in contacts]
        self.reference = refs[0][1].owner
        rest = next(
            k
            for k, (fa, fb, _) in enumerate(refs)
            if isinstance(fa.feature, Face) and isinstance(fb.feature, Face)
        )
        face_a, face_b = refs[rest][0].feature, refs[rest][1].feature
        assert isinstance(face_a, Face) and isinstance(face_b, Face)
        n_a, n_b = face_a.normal, face_b.normal
        r0 = pin.Quaternion.FromTwoVectors(np.asarray(n_a, float), -np.asarray(n_b, float)).matrix()
        k = pin.skew(np.asarray(n_a, float))
        # R(w) = A0 + cos w · A1 + sin w · A2 (Rodrigues)
        self._a0 = r0 @ (np.eye(3) + k @ k)
        self._a1 = -r0 @ k @ k
        self._a2 = r0 @ k
        self.vertices = object_vertices(graph.nodes[obj].shape)
        self._centroid = self.vertices.mean(axis=0)

        normals, points, levels = [], [], []
        planes: list[tuple[FloatArray, float]] = []
        aligned: list[tuple[FloatArray, FloatArray]] = []
        inside: list[tuple[FloatArray, FloatArray]] = []
        outline: FloatArray | None = None
        for k, (fa, fb, contact) in enumerate(refs):
            b = fb.feature
            assert isinstance(b, Face)  # the loader's rule: b is a face
            level = float(b.normal @ b.point)
            on = _points_on_plane(fa)
            normals += [b.normal] * len(on)
            points += on
            levels += [level] * len(on)
            planes.append((b.normal, level))
            if isinstance(fa.feature, Face) and k != rest:
                aligned.append((fa.feature.normal, b.normal))
            if contact.kind == "inside_of":
                inside += b.inward_edge_normals()
                if outline is None:
                    outline = b.outline
        g = np.array(normals, dtype=float)
        self._normals, self._points = g, np.array(points, dtype=float)
        self._levels = np.array(levels, dtype=float)
        self._plane_n = np.array([n for n, _ in planes], dtype=float)
        self._plane_l = np.array([lv for _, lv in planes], dtype=float)
        self._inside_m = np.array([m for m, _ in inside], dtype=float).reshape(-1, 3)
        self._inside_q = np.array([q for _, q in inside], dtype=float).reshape(-1, 3)

        u, s, vt = np.linalg.svd(g)
        rank = int(np.sum(s > 1e-12 * s[0]))
        self._pinv = vt[:rank].T @ np.diag(1.0 / s[:rank]) @ u[:, :rank].T  # G⁺ (3, m)
        self.free = vt[rank:].T  # N (3, d)
        # r(w) = c0 + cos w · cc + sin w · cs, one entry per point-on-plane row
        self._c0 = self._levels - np.einsum("ij,ij->i", g, self._points @ self._a0.T)
        self._cc = -np.einsum("ij,ij->i", g, self._points @ self._a1.T)
        self._cs = -np.einsum("ij,ij->i", g, self._points @ self._a2.T)
        conditions = [
            _Sinusoid(float(lam @ self._c0), float(lam @ self._cc), float(lam @ self._cs))
            for lam in u[:, rank:].T
        ]
        for na, nb in aligned:  # R(w) n_a′ + n_b′ = 0, componentwise
            c0, cc, cs = self._a0 @ na + nb, self._a1 @ na, self._a2 @ na
            conditions += [_Sinusoid(float(c0[j]), float(cc[j]), float(cs[j])) for j in range(3)]
        self.roots = self._roots([c for c in conditions if not c.trivial])

        d = self.free.shape[1]
        if d and outline is None:
            raise SpecError(
                self.where,
                f"the contacts leave {obj!r} free to slide without bound; the replay cannot "
                "sample its true pose (add an inside_of contact)",
            )
        if d:
            assert outline is not None
            along = outline @ self.free
            self._t_lo, self._t_span = along.min(axis=0), np.ptp(along, axis=0)
        else:
            self._t_lo, self._t_span = np.zeros(0), np.zeros(0)

    def _roots(self, conditions: list[_Sinusoid]) -> tuple[float, ...] | None:
        """None when w is free; else the values of w every condition allows."""
        if not conditions:
            return None
        first = max(conditions, key=lambda c: math.hypot(c.kc, c.ks))
        roots = tuple(w for w in first.roots() if all(abs(c(w)) <= 1e3 * SLACK for c in conditions))
        if not roots:
            raise SpecError(self.where, f"no pose of {self.obj!r} satisfies these contacts")
        return roots

    def rotation(self, w: FloatArray) -> FloatArray:
        """R(w) for an array of angles: shape (n, 3, 3)."""
        c, s = np.cos(w)[:, None, None], np.sin(w)[:, None, None]
        return np.asarray(self._a0 + c * self._a1 + s * self._a2)

    def draw(self, rng: np.random.Generator, n: int) -> list[pin.SE3]:
        """The accepted poses among ``n`` candidates, in the order drawn (module docstring)."""
        rot, pos = self._candidates(rng, n)
        return [pin.SE3(rot[i], pos[i]) for i in np.flatnonzero(self.accepts(rot, pos))]

    def sample(self, rng: np.random.Generator) -> pin.SE3:
        """One pose: the first accepted candidate, drawn in growing batches (module docstring)."""
        drawn, batch = 0, _FIRST_BATCH
        while drawn < MAX_CANDIDATES:
            size = min(batch, MAX_CANDIDATES - drawn)
            rot, pos = self._candidates(rng, size)
            ok = np.flatnonzero(self.accepts(rot, pos))
            if ok.size:
                i = int(ok[0])
                return pin.SE3(rot[i], pos[i])
            drawn += size
            batch = min(2 * batch, _MAX_BATCH)
        raise SpecError(
            self.where,
            f"none of {MAX_CANDIDATES} candidate poses of {self.obj!r} satisfies its contacts "
            f"(acceptance below {1.0 / MAX_CANDIDATES:.1e}): the set they leave is too thin "
            "for the replay to sample its true pose",
        )

    def _candidates(self, rng: np.random.Generator, n: int) -> tuple[FloatArray, FloatArray]:
        """Proposals (R, P), ``n`` of them: w on the circle or its roots, t on the centroid box."""
        if self.roots is None:
            w = rng.uniform(-math.pi, math.pi, n)
        else:
            w = np.asarray(self.roots)[rng.integers(0, len(self.roots), n)]
        rot = self.rotation(w)
        c, s = np.cos(w)[:, None], np.sin(w)[:, None]
        pos = (self._c0 + c * self._cc + s * self._cs) @ self._pinv.T
        if self.free.shape[1]:
            u = rng.uniform(0.0, 1.0, (n, self.free.shape[1]))
            centroid = rot @ self._centroid
            t = self._t_lo + u * self._t_span - centroid @ self.free
            pos = pos + t @ self.free.T
        return rot, pos

    def accepts(self, rot: FloatArray, pos: FloatArray) -> NDArray[np.bool_]:
        """Which poses satisfy every contact's exact inequalities (module docstring)."""
        world = pos[:, None, :] + np.einsum("nij,vj->nvi", rot, self.vertices)  # (n, 8, 3)
        free_side = np.einsum("nvi,pi->npv", world, self._plane_n) - self._plane_l[None, :, None]
        ok = np.all(free_side >= -SLACK, axis=(1, 2))
        if self._inside_m.shape[0]:
            inside = (
                np.einsum("nvi,ki->nkv", world, self._inside_m)
                - np.einsum("ki,ki->k", self._inside_q, self._inside_m)[None, :, None]
            )
            ok &= np.all(inside >= -SLACK, axis=(1, 2))
        return ok

    def residuals(self, pose: pin.SE3) -> FloatArray:
        """The point-on-plane residuals ``n̂ᵢ·(P + R pᵢ) − ℓᵢ`` of a pose [m] (all 0 on contact)."""
        world = self._points @ pose.rotation.T + pose.translation
        return np.asarray(np.einsum("ij,ij->i", self._normals, world) - self._levels)


def _points_on_plane(ref: FeatureRef) -> list[FloatArray]:
    """The points of feature ``a`` (its object's frame) that its contact puts on b's plane."""
    a = ref.feature
    if isinstance(a, Face):
        return [a.point]
    if isinstance(a, Edge):
        return [a.start, a.end]
    assert isinstance(a, Corner)
    return [a.point]


_PLACEMENTS: weakref.WeakKeyDictionary[AttributeGraph, Mapping[str, ContactPlacement]] = (
    weakref.WeakKeyDictionary()
)


def located_objects(graph: AttributeGraph) -> Mapping[str, ContactPlacement]:
    """Every object the task's contacts locate → its sampler (cached per graph, weakly)."""
    cached = _PLACEMENTS.get(graph)
    if cached is None:
        contacts = graph.spec.contacts
        groups = contact_groups(graph, contacts) if contacts else {}
        cached = {
            obj: ContactPlacement(graph, obj, tuple((i, contacts[i]) for i in idx))
            for obj, idx in groups.items()
        }
        _PLACEMENTS[graph] = cached
    return cached
