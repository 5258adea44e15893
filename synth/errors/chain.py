"""Relation chains: ``from⁻¹ ∘ to`` as a product of fixed links and perturbed links.

Seed A.2 (L3215–3225): ``T_ht = hole⁻¹ ∘ tip = T_bh⁻¹ ∘ box⁻¹ ∘ hand ∘ T_hd ∘ T_ds ∘ T_st``.
A link with uncertainty is ``N ∘ E(v)`` with ``E(v) = transl(x, y, z) ∘ rot(x̂, rx) ∘ rot(ŷ, ry)
∘ rot(ẑ, rz)`` in the link's own frame (the seed's Δhand, L3195). A chain is a list of terms,
each a fixed ``SE3`` or a (possibly inverted) perturbation of one parameter block; the planner
builds chains of its own (hand errors at a program point) with the same terms.

Two evaluations of one chain:

* :meth:`ErrorChain.pose_model` — the Taylor model (first-order terms + rigorous remainder);
* :meth:`ErrorChain.evaluate` — the exact nonlinear chain for a batch of parameter vectors
  (the Monte Carlo oracle), vectorised with numpy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from synth.errors.locate import located_graph
from synth.errors.parameters import ParameterBlock, ParameterSpace
from synth.errors.taylor import PoseModel, TaylorModel
from synth.models.graph import AttributeGraph, Link

_AXIS = {"x": 0, "y": 1, "z": 2, "rx": 0, "ry": 1, "rz": 2}


@dataclass(frozen=True, eq=False)
class Fixed:
    """A known transform in the chain."""

    pose: pin.SE3


@dataclass(frozen=True, eq=False)
class Perturbation:
    """``E(v_block)`` (or its inverse) of block number ``block`` of the space."""

    block: int
    inverse: bool = False


Term = Fixed | Perturbation


@dataclass(frozen=True, eq=False)
class ErrorChain:
    """A relation as a product of terms over one parameter space."""

    space: ParameterSpace
    terms: tuple[Term, ...]

    @property
    def nominal(self) -> pin.SE3:
        """The relation with every error parameter zero."""
        pose = pin.SE3.Identity()
        for t in self.terms:
            if isinstance(t, Fixed):
                pose = pose * t.pose
        return pose

    def pose_model(self) -> PoseModel:
        """The Taylor model of the whole relation (first order + certified remainder).

        With fixed parts ``F_k`` and perturbations ``E_k``, ``T = F₀E₁F₁…E_nF_n`` is rewritten
        exactly as ``T = T₀ ∏_k S_k⁻¹ E_k S_k`` with ``T₀ = F₀F₁…F_n`` and ``S_k = F_k…F_n``. Each
        conjugated factor is an error seen from the end frame, whose lever arm is the local
        distance from the error's frame to the end — not the world coordinates that would
        cancel in exact arithmetic but not in interval arithmetic.
        """
        m = self.space.magnitude
        offsets = self.space.offsets
        suffix = pin.SE3.Identity()
        conjugated: list[PoseModel] = []
        for t in reversed(self.terms):
            if isinstance(t, Fixed):
                suffix = t.pose * suffix
                continue
            factor = _perturbation_model(self.space.blocks[t.block], offsets[t.block], m)
            if t.inverse:
                factor = factor.inverse()
            conjugated.append(_constant(suffix.inverse(), m) * factor * _constant(suffix, m))
        pose = _constant(self.nominal, m)
        for factor in reversed(conjugated):
            pose = pose * factor
        return pose

    def evaluate(self, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Exact ``(R, p)`` of the relation for each row of ``v``: shapes (N, 3, 3), (N, 3)."""
        v = np.atleast_2d(np.asarray(v, dtype=float))
        n = v.shape[0]
        rot = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
        pos = np.zeros((n, 3))
        offsets = self.space.offsets
        for t in self.terms:
            if isinstance(t, Fixed):
                r2 = np.broadcast_to(t.pose.rotation, (n, 3, 3))
                p2 = np.broadcast_to(t.pose.translation, (n, 3))
            else:
                block = self.space.blocks[t.block]
                r2, p2 = _perturbation_exact(
                    block, v[:, offsets[t.block] : offsets[t.block] + block.size]
                )
                if t.inverse:
                    r2 = np.swapaxes(r2, 1, 2)
                    p2 = -np.einsum("nij,nj->ni", r2, p2)
            pos = pos + np.einsum("nij,nj->ni", rot, p2)
            rot = np.einsum("nij,njk->nik", rot, r2)
        return rot, pos


def _elementary(axis: int, angle: np.ndarray) -> np.ndarray:
    """Batch of ``rot(axis, angle)`` matrices."""
    c, s = np.cos(angle), np.sin(angle)
    n = angle.shape[0]
    r = np.zeros((n, 3, 3))
    i, j = (axis + 1) % 3, (axis + 2) % 3
    r[:, axis, axis] = 1.0
    r[:, i, i] = c
    r[:, j, j] = c
    r[:, j, i] = s
    r[:, i, j] = -s
    return r


def _perturbation_exact(block: ParameterBlock, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = v.shape[0]
    p = np.zeros((n, 3))
    r = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
    for k, name in enumerate(block.names):
        if name in ("x", "y", "z"):
            p[:, _AXIS[name]] += v[:, k]
    for k, name in enumerate(block.names):  # rot(x̂) ∘ rot(ŷ) ∘ rot(ẑ), in that order
        if name in ("rx", "ry", "rz"):
            r = np.einsum("nij,njk->nik", r, _elementary(_AXIS[name], v[:, k]))
    return r, p


def _constant(pose: pin.SE3, m: np.ndarray) -> PoseModel:
    return PoseModel(
        TaylorModel.constant(pose.rotation, m), TaylorModel.constant(pose.translation, m)
    )


def _perturbation_model(block: ParameterBlock, offset: int, m: np.ndarray) -> PoseModel:
    trans = TaylorModel.constant(np.zeros(3), m)
    rot = TaylorModel.constant(np.eye(3), m)
    for k, name in enumerate(block.names):
        if name in ("x", "y", "z"):
            trans = trans + TaylorModel.translation(_AXIS[name], offset + k, m)
        else:
            rot = rot @ TaylorModel.rotation(_AXIS[name], offset + k, m)
    return PoseModel(rot, trans)


def chain_between(graph: AttributeGraph, start: str, end: str) -> ErrorChain:
    """The chain for ``start⁻¹ ∘ end`` through the frame tree, one block per uncertain link.

    ``start⁻¹ ∘ ancestor = ∏ (N_k E_k)⁻¹`` over the links from ``start`` upwards, then
    ``ancestor⁻¹ ∘ end = ∏ N_k E_k`` down to ``end`` (seed A.2, L3215). Links of objects
    located by contacts (seed A.1) take their derived pose and block: the extension point is
    :func:`synth.errors.locate.located_graph`, which returns ``graph`` itself otherwise.
    """
    graph = located_graph(graph, start, end)
    path = graph.path(start, end)
    blocks: list[ParameterBlock] = []
    terms: list[Term] = []

    def block_of(link: Link) -> int | None:
        if link.uncertainty is None or not link.uncertainty.bounds():
            return None
        blocks.append(ParameterBlock.from_uncertainty(link.child, link.uncertainty))
        return len(blocks) - 1

    for link in path.up:
        b = block_of(link)
        if b is not None:
            terms.append(Perturbation(b, inverse=True))
        terms.append(Fixed(link.parent_from_child.inverse()))
    for link in path.down:
        terms.append(Fixed(link.parent_from_child))
        b = block_of(link)
        if b is not None:
            terms.append(Perturbation(b))
    return ErrorChain(ParameterSpace(tuple(blocks)), tuple(terms))
