"""Pin-to-hole error chains of a candidate strategy (seed §4.5, Eqn 3.5.1, L2205).

"For each strategy, we ... estimate the error between the pin and hole at the approach point
as a function of free variables" (L2203). The relation is ``hole⁻¹ ∘ end``, the inserted pin
end seen from the hole:

* the hole side is the attribute graph's chain from the world down to the hole, one
  perturbation ``E(v) = transl ∘ rot_x ∘ rot_y ∘ rot_z`` per uncertain link (seed A.2, L3195);
* the pin side hangs from the hand's *nominal* pose at that program point — the arm goes where
  the program believes the hole is (tests/data/seed_4_5.yaml) — with the hand's error block,
  then the grasp ``T_hand_pin`` read from the candidate's world (the pin is affixed there), the
  grasp determination block if the world has one (NILTRANS: none, L2630), and ``T_pin_end``.

So ``hole(v)⁻¹ ∘ hand₀ ∘ E_hand(v) ∘ T_hand_pin ∘ [E_grasp(v)] ∘ T_pin_end``. A tap adds a
second relation over the *same* parameter space (shared box block, own hand block, a
measurement variable): see :func:`tap_relations` and :mod:`synth.strategies.tapping`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial

import numpy as np
import pinocchio as pin

from synth.errors.chain import ErrorChain, Fixed, Perturbation, Term
from synth.errors.parameters import ParameterBlock, ParameterSpace
from synth.models.graph import AttributeGraph
from synth.models.spec import WORLD
from synth.models.uncertainty import Uncertainty
from synth.models.world import World
from synth.strategies.context import PlanContext
from synth.strategies.hypotheses import Affixed, ApproachStandoff, Bounds, GraspDetermination
from synth.strategies.records import Grasp

MEASUREMENT = "tap.measurement"
"""Owner of the tap's measurement variable m [m] (a one-parameter ``z`` block)."""


@dataclass
class SpaceBuilder:
    """Blocks of one parameter space, registered once per key so chains can share them."""

    blocks: list[ParameterBlock] = field(default_factory=list)
    index: dict[str, int] = field(default_factory=dict)

    def block(self, key: str, make: Callable[[], ParameterBlock]) -> int:
        """Index of the block registered under ``key`` (made on first use)."""
        if key not in self.index:
            self.index[key] = len(self.blocks)
            self.blocks.append(make())
        return self.index[key]

    def space(self) -> ParameterSpace:
        """The space of every block registered so far."""
        return ParameterSpace(tuple(self.blocks))


def hole_frame_offset(phi: float, offset: tuple[float, float, float]) -> pin.SE3:
    """``trans(rot(ẑ, φ), offset)``: a frame in the hole frame [rad, m]."""
    return pin.SE3(pin.exp3(np.array([0.0, 0.0, phi])), np.array(offset, dtype=float))


def box_block(owner: str, bounds: tuple[tuple[str, float, float], ...]) -> ParameterBlock:
    """A block with bounds only: ``((param, lo, hi), …)`` in canonical order."""
    names = tuple(b[0] for b in bounds)
    return ParameterBlock(
        owner=owner,
        names=names,
        lo=np.array([b[1] for b in bounds], dtype=float),
        hi=np.array([b[2] for b in bounds], dtype=float),
        a_ub=np.zeros((0, len(names))),
        b_ub=np.zeros(0),
    )


def _link_block(owner: str, unc: Uncertainty) -> ParameterBlock:
    return ParameterBlock.from_uncertainty(owner, unc)


def frame_inverse_terms(graph: AttributeGraph, frame: str, builder: SpaceBuilder) -> list[Term]:
    """Terms of ``frame(v)⁻¹`` (world to frame): ``E₁⁻¹ N₁⁻¹ E₂⁻¹ N₂⁻¹ …``, child link first.

    The same construction as :func:`synth.errors.chain.chain_between` towards the world, but
    registering each uncertain link's block in ``builder`` (key ``link:<frame>``) so that two
    relations through the same box share its errors.
    """
    terms: list[Term] = []
    for link in graph.path(frame, WORLD).up:
        unc = link.uncertainty
        if unc is not None and unc.bounds():
            index = builder.block(f"link:{link.child}", partial(_link_block, link.child, unc))
            terms.append(Perturbation(index, inverse=True))
        terms.append(Fixed(link.parent_from_child.inverse()))
    return terms


def held_end_terms(
    ctx: PlanContext,
    world: World,
    world_from_hand: pin.SE3,
    builder: SpaceBuilder,
    hand_key: str,
) -> list[Term]:
    """Terms of the true pin end: ``hand₀ ∘ E_hand ∘ T_hand_pin ∘ [E_grasp] ∘ T_pin_end``.

    The grasp comes from the world's :class:`Affixed` fact and the grasp determination from
    its :class:`GraspDetermination`: no block when exact, else ``(param, lo, hi)`` bounds of
    the pin's error in the hand (:func:`grasped_end_terms`).
    """
    grasp = world.get(Affixed, ctx.pin_al, ctx.hand_al).grasp
    residual = world.get(GraspDetermination, ctx.pin_al).residual
    return grasped_end_terms(ctx, grasp, residual, world_from_hand, builder, hand_key)


def grasped_end_terms(
    ctx: PlanContext,
    grasp: Grasp,
    residual: Bounds | None,
    world_from_hand: pin.SE3,
    builder: SpaceBuilder,
    hand_key: str,
) -> list[Term]:
    """:func:`held_end_terms` of the pin held by ``grasp``, ``residual`` its error in the hand."""
    terms: list[Term] = [Fixed(world_from_hand)]
    if ctx.hand_error is not None and ctx.hand_error.bounds():
        unc = ctx.hand_error
        owner = f"{ctx.hand_al}@{hand_key.split(':')[-1]}"
        index = builder.block(hand_key, lambda: ParameterBlock.from_uncertainty(owner, unc))
        terms.append(Perturbation(index))
    terms.append(Fixed(grasp.pin_from_hand().inverse()))
    if residual:
        index = builder.block("grasp", lambda: box_block(f"{ctx.pin_al}@grasp", residual))
        terms.append(Perturbation(index))
    terms.append(Fixed(ctx.pin_from_end))
    return terms


def hand_for_end(ctx: PlanContext, world: World, world_from_end: pin.SE3) -> pin.SE3:
    """Nominal world pose of the hand holding the pin end at ``world_from_end``."""
    grasp = world.get(Affixed, ctx.pin_al, ctx.hand_al).grasp
    return hand_holding_end(ctx, grasp, world_from_end)


def hand_holding_end(ctx: PlanContext, grasp: Grasp, world_from_end: pin.SE3) -> pin.SE3:
    """:func:`hand_for_end` of the pin held by ``grasp``."""
    return world_from_end * ctx.pin_from_end.inverse() * grasp.pin_from_hand()


def approach_standoff(ctx: PlanContext, world: World) -> float:
    """The approach height [m] of ``world``'s candidate.

    Its :class:`ApproachStandoff` fact (:mod:`synth.strategies.approach` derives it
    from Δz), else the option's.
    """
    fact = world.find(ApproachStandoff, ctx.pin_al, ctx.hole_al)
    return ctx.options.standoff if fact is None else fact.standoff


def approach_relation(ctx: PlanContext, world: World, phi: float) -> ErrorChain:
    """``hole⁻¹ ∘ end`` with the pin at the approach point (seed §4.5, L2203).

    The approach point is ``hole ∘ trans(rot(ẑ, φ), (0, 0, standoff))``, with the candidate's
    standoff (:func:`approach_standoff`).
    """
    builder = SpaceBuilder()
    terms = frame_inverse_terms(ctx.graph, ctx.hole_frame, builder)
    end = ctx.world_hole * hole_frame_offset(phi, (0.0, 0.0, approach_standoff(ctx, world)))
    terms += held_end_terms(ctx, world, hand_for_end(ctx, world, end), builder, "hand:approach")
    return ErrorChain(builder.space(), tuple(terms))


def hole_only_relation(ctx: PlanContext) -> ErrorChain:
    """``hole⁻¹ ∘ end`` with an exactly placed pin end at the approach point.

    "Assuming that there is no error in the arm or grasp, so that all error between pin and
    hole comes from errors in the hole location" (L2476): the basis of the minimum refinement
    cost. Its first-order support in any direction is at most that of every candidate's
    relation (the candidates add hand error blocks to the same box terms).
    """
    builder = SpaceBuilder()
    terms = frame_inverse_terms(ctx.graph, ctx.hole_frame, builder)
    end = ctx.world_hole * hole_frame_offset(0.0, (0.0, 0.0, ctx.options.standoff))
    terms.append(Fixed(end))
    return ErrorChain(builder.space(), tuple(terms))


@dataclass(frozen=True, eq=False)
class TapRelations:
    """The insertion and tap relations over one parameter space.

    ``insertion`` is ``hole⁻¹ ∘ end`` at the approach point; ``contact`` is the tap point on
    the true surface seen from itself, ``X⁻¹ ∘ hole(v)⁻¹ ∘ T_n ∘ trans(0, 0, m) ∘ T_end_hand⁻¹
    ∘ E_hand' ∘ T_hand_pin ∘ T_pin_end``, whose z is the pin end's height above the true
    surface when the program believes the end is ``m`` above the nominal tap point ``T_n =
    hole₀ ∘ X``. The tap stops on contact, so z = 0 there; ``m`` is what ``CORR`` reads (seed
    L2826). ``measurement`` is the index of m in the space.
    """

    insertion: ErrorChain
    contact: ErrorChain
    measurement: int


def tap_relations(
    ctx: PlanContext,
    world: World,
    phi: float,
    offset: tuple[float, float, float],
    measurement_bound: float,
) -> TapRelations:
    """Build :class:`TapRelations` for a tap at ``offset`` [m] (hole frame), pin turned by φ.

    ``measurement_bound`` [m] bounds |m| (the surface height the tap can find, see
    :func:`synth.strategies.tapping.measurement_bound`). Hand errors at the tap and at the
    insertion are separate blocks unless the options say they are ``repeatable``.
    """
    builder = SpaceBuilder()
    hole_terms = frame_inverse_terms(ctx.graph, ctx.hole_frame, builder)
    standoff = approach_standoff(ctx, world)
    end_approach = ctx.world_hole * hole_frame_offset(phi, (0.0, 0.0, standoff))
    insertion = hole_terms + held_end_terms(
        ctx, world, hand_for_end(ctx, world, end_approach), builder, "hand:approach"
    )
    tap_key = "hand:approach" if ctx.options.tap_hand_errors == "repeatable" else "hand:tap"
    point = hole_frame_offset(phi, offset)
    nominal_tap = ctx.world_hole * point
    m_index = builder.block(
        MEASUREMENT,
        lambda: box_block(MEASUREMENT, (("z", -measurement_bound, measurement_bound),)),
    )
    contact: list[Term] = [Fixed(point.inverse()), *hole_terms]
    contact += [Fixed(nominal_tap), Perturbation(m_index)]
    end_from_hand = hand_for_end(ctx, world, pin.SE3.Identity())
    contact += held_end_terms(ctx, world, end_from_hand, builder, tap_key)
    space = builder.space()
    return TapRelations(
        ErrorChain(space, tuple(insertion)),
        ErrorChain(space, tuple(contact)),
        space.offsets[m_index],
    )
