"""The true world of one replay trial: object poses and the arm's positioning errors.

The program believes the task's *nominal* locations (:mod:`synth.codegen.binding`). The replay
runs it against a world it does not know exactly, sampled here from the task itself — never from the
planner's estimates (design card: "the replay is the referee").

**Object poses.** Every link with an uncertainty block is perturbed once per trial:

    T_parent_child = N ∘ E(v),   E(v) = transl(x, y, z) ∘ rot(x̂, rx) ∘ rot(ŷ, ry) ∘ rot(ẑ, rz),

in the link's own frame (seed A.2, L3190–3200; the convention of :mod:`synth.models.spec` and
:mod:`synth.errors.chain`). ``v`` is drawn by :meth:`ParameterSpace.sample` with the block's
distribution (uniform on the feasible set, or normal with σ = tolerance/3 truncated at the
bounds, seed L7242), all blocks of the task in one draw. True world poses are composed down the
frame tree from the true links.

**Objects located by contacts** (the task's ``contacts:``, seed A.1) are not perturbed around
a nominal: their true pose in their parent's frame is drawn from the contacts themselves, after
the blocks, uniformly on the set of poses the contacts allow (:mod:`synth.replay.located`),
whatever the distribution. The graph may carry the program's belief about such an object too
(:func:`synth.replay.run.replay_graph` gives it the pose and block the planner derived): the
belief is then only the reference its error is reported against, E = N⁻¹ ∘ T, never where the
truth is drawn.

**Hand positioning error** (the task's ``manipulator.hand_error``, seed A.2 L3195: ±0.05 in,
±0.25°). The arm reaches each commanded hand target only up to an error E drawn afresh for
every target of every motion (destination and each via point), applied on the right, in the
hand frame: true hand = commanded ∘ E. The arm's own reading of its hand (what AL calls BMANIP,
"sensed", al-language.md §8.3) is the commanded pose; the error is what the arm does not know.

**Pin in the hand.** None by default, as the seed assumes ("we assume that the hand holds the
pin with essentially no error", L2244; its strategy records print ``GRASP DETERM: NILTRANS``,
L2693): see :class:`synth.replay.machine.ReplayMachine` for how ``CENTER`` registers the hand on
the pin. The task schema has no pin-in-hand error block, and the seed's fixtures need none.

The nominal world (:func:`nominal_world`, :meth:`HandErrors.none`) has every error zero: the
true world equals the program's beliefs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from synth.errors.parameters import ParameterBlock, ParameterSpace
from synth.models.graph import AttributeGraph
from synth.models.spec import WORLD
from synth.models.uncertainty import Uncertainty
from synth.replay.located import located_objects
from synth.replay.report import HandDraw

__all__ = [
    "HandErrors",
    "TrueWorld",
    "error_parameters",
    "link_error",
    "nominal_world",
    "sample_world",
]

_AXES = {"x": 0, "y": 1, "z": 2, "rx": 0, "ry": 1, "rz": 2}
_HAND_BATCH = 32
"""Hand errors drawn per batch from a trial's generator (the stream is reproducible)."""


def link_error(names: tuple[str, ...], values: np.ndarray) -> pin.SE3:
    """E(v) = transl(x, y, z) ∘ rot(x̂, rx) ∘ rot(ŷ, ry) ∘ rot(ẑ, rz) [m, rad] (seed L3195).

    ``names`` lists the bounded parameters (a subset of x, y, z, rx, ry, rz in that order) and
    ``values`` their values; missing parameters are zero.
    """
    translation = np.zeros(3)
    rotation = np.eye(3)
    for name, value in zip(names, np.asarray(values, dtype=float), strict=True):
        if name in ("x", "y", "z"):
            translation[_AXES[name]] = value
    for axis in ("rx", "ry", "rz"):  # rot(x̂) ∘ rot(ŷ) ∘ rot(ẑ), in that order
        if axis in names:
            unit = np.zeros(3)
            unit[_AXES[axis]] = 1.0
            rotation = rotation @ pin.exp3(unit * float(values[names.index(axis)]))
    return pin.SE3(rotation, translation)


def error_parameters(error: pin.SE3) -> dict[str, float]:
    """The inverse of :func:`link_error`: (x, y, z, rx, ry, rz) [m, rad] of ``error``.

    With R = rot(x̂, rx)·rot(ŷ, ry)·rot(ẑ, rz): ``ry = asin R₀₂``, ``rx = atan2(−R₁₂, R₂₂)``,
    ``rz = atan2(−R₀₁, R₀₀)`` (|ry| < 90°).
    """
    r, t = error.rotation, error.translation
    return {
        "x": float(t[0]),
        "y": float(t[1]),
        "z": float(t[2]),
        "rx": math.atan2(-r[1, 2], r[2, 2]),
        "ry": math.asin(min(max(float(r[0, 2]), -1.0), 1.0)),
        "rz": math.atan2(-r[0, 1], r[0, 0]),
    }


@dataclass(frozen=True, eq=False)
class TrueWorld:
    """The true poses of one trial.

    ``world_from`` maps every task frame name to its true world pose [m]; ``link_errors`` maps
    each perturbed frame to its error E (parent side, see the module docstring; for a located
    object the error of its drawn pose against the graph's belief); ``nominal`` is True for the
    believed world (every error zero).
    """

    world_from: Mapping[str, pin.SE3]
    link_errors: Mapping[str, pin.SE3]
    nominal: bool
    parameters: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    """The sampled error parameters per perturbed frame [m, rad]: ``{frame: {"x": …}}`` (a
    located object's are :func:`error_parameters` of its error, all six)."""

    def pose(self, frame: str) -> pin.SE3:
        """True world pose of ``frame`` [m] (a copy)."""
        return pin.SE3(self.world_from[frame])


def _compose(graph: AttributeGraph, errors: Mapping[str, pin.SE3]) -> dict[str, pin.SE3]:
    out: dict[str, pin.SE3] = {}
    order = sorted(graph.nodes, key=lambda n: len(graph.ancestors(n)))
    for name in order:
        link = graph.links[name]
        parent = pin.SE3.Identity() if link.parent == WORLD else out[link.parent]
        local = link.parent_from_child
        error = errors.get(name)
        if error is not None:
            local = local * error
        out[name] = parent * local
    return out


def nominal_world(graph: AttributeGraph) -> TrueWorld:
    """The believed world: every frame at its nominal pose (``graph.world_from``)."""
    return TrueWorld(_compose(graph, {}), {}, nominal=True)


def _uncertain_links(
    graph: AttributeGraph, located: Mapping[str, object]
) -> list[tuple[str, Uncertainty]]:
    return [
        (name, link.uncertainty)
        for name, link in graph.links.items()
        if link.uncertainty is not None and link.uncertainty.bounds() and name not in located
    ]


def sample_world(graph: AttributeGraph, rng: np.random.Generator) -> TrueWorld:
    """One true world (see the module docstring).

    The uncertain links perturbed by a draw of their blocks, then the located objects drawn
    from their contacts, from ``rng`` in that order.
    """
    located = located_objects(graph)
    links = _uncertain_links(graph, located)
    errors: dict[str, pin.SE3] = {}
    parameters: dict[str, dict[str, float]] = {}
    if links:
        blocks = tuple(ParameterBlock.from_uncertainty(name, unc) for name, unc in links)
        space = ParameterSpace(blocks)
        v = space.sample(rng, 1)[0]
        for b in blocks:  # owners are distinct frame names
            values = v[space.block_slice(b.owner)]
            errors[b.owner] = link_error(b.names, values)
            parameters[b.owner] = dict(zip(b.names, map(float, values), strict=True))
    for name, placement in located.items():
        error = graph.links[name].parent_from_child.actInv(placement.sample(rng))
        errors[name] = error
        parameters[name] = error_parameters(error)
    return TrueWorld(_compose(graph, errors), errors, nominal=False, parameters=parameters)


class HandErrors:
    """A reproducible stream of hand positioning errors E [m, rad], one per hand target.

    Built from the task's ``manipulator.hand_error`` block and a generator of its own; draws
    are made in batches of 32 with :meth:`ParameterSpace.sample` (the block's distribution and
    constraints), so the stream depends only on the generator's seed. :meth:`none` gives the
    errorless stream of the nominal run.
    """

    def __init__(self, block: Uncertainty | None, rng: np.random.Generator | None) -> None:
        self._space: ParameterSpace | None = None
        self._names: tuple[str, ...] = ()
        if block is not None and block.bounds():
            if rng is None:
                raise ValueError("a hand error block needs a random generator")
            parameters = ParameterBlock.from_uncertainty("hand", block)
            self._space = ParameterSpace((parameters,))
            self._names = parameters.names
        self._rng = rng
        self._batch = np.zeros((0, len(self._names)))
        self.drawn = 0
        """Number of errors drawn so far."""
        self.draws: list[HandDraw] = []
        """The errors drawn so far, each with its motion's AL line (none for the exact stream)."""
        self._visits: dict[int | None, int] = {}

    @classmethod
    def none(cls) -> HandErrors:
        """The nominal stream: every error is the identity."""
        return cls(None, None)

    @property
    def exact(self) -> bool:
        """True when every error is the identity."""
        return self._space is None

    def next(self, line: int | None = None, target: int = 1) -> pin.SE3:
        """The error of the next hand target: E = transl ∘ rot(x̂) ∘ rot(ŷ) ∘ rot(ẑ).

        ``line``, ``target``: the AL line of the motion the target belongs to and its place
        among the motion's targets (from 1), kept with the draw (:attr:`draws`) so a trial's
        report can say which motion drew which error.
        """
        self.drawn += 1
        if self._space is None:
            return pin.SE3.Identity()
        if self._batch.shape[0] == 0:
            assert self._rng is not None
            self._batch = self._space.sample(self._rng, _HAND_BATCH)
        v, self._batch = self._batch[0], self._batch[1:]
        if target == 1:
            self._visits[line] = self._visits.get(line, 0) + 1
        values = tuple((n, float(x)) for n, x in zip(self._names, v, strict=True))
        self.draws.append(HandDraw(line, target, values, self._visits.get(line, 1)))
        return link_error(self._names, v)
