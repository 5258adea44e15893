"""Gross motions clear of the workcell: the planner's swept check of the moves between sites.

The seed's code writers check the geometry of a grasp (§4.3.1, L2048–2070) and leave the path
between sites to the arm. AL moves are joint-interpolated (seed L3846), and a joint-interpolated
move of the Stanford arm swings the hand in an arc about the column, which can pass through an
object that the straight line between the two sites misses: with the seed_4_8 arm at
(20, 80) cm, the planner's move from BPARK to the rack swept finger_left through BOX, and the
replay refused the program. So every candidate's gross motions are swept here, with
Coal and conservative advancement (:func:`synth.models.arm.swept_path`), along the straight
joint-space segments between the configurations the program will move through: each target
solved nearest the configuration before it, from the park on
(:func:`synth.models.arm.nearest_solution`, the replay's rule too;
``tests/test_plan_clearance.py`` checks that they agree):

1. ``park → grasp approach``: empty hand, fingers at the approach opening (L2139); every solid
   of the workcell (:mod:`synth.models.workcell`: table, boxes, racks, fixtures) and the pin
   standing in its start hole;
2. ``departure → hole approach`` (and, for a tap, ``departure → tap via``): the pin held at the
   grasp, fingers closed on it, the same solids without the pin.

The believed workcell is not the true one, so each pair must keep the 1 mm clearance plus how
far either body may be from its believed place:

* a solid under uncertain links L (its own, or its ancestors'): a directional bound
  (:class:`~synth.models.arm.sweep.Displacement`, ``SweepOptions.displacements``): along the
  direction n between the closest points, Σ_L (Σ_i |n_i|·t_i + Σ_i √(1 − n_i²)·2 sin(θ_i/2)·λ_i)
  with n in L's frame, t_i and θ_i the link's bounds per axis and λ_i the lever about L's axis
  i of the solid's farthest hull vertex (a curved solid: r_L, the radius about L's origin of a
  ball holding it). A part with sideways errors and an exact height has no vertical margin; a
  plate tilting about its centre is charged at its corners' levers about each axis, not at
  r_L about both. The ball bound Σ_L (|t|_max + Σ 2 sin(θ_i/2)·λ_i) applies only where the
  direction is unknown. The sum is exact as a bound: each link's error moves the subtree
  rigidly;
* the hand and what it carries, and the wrist bodies (the last three joints), under the arm's
  positioning error (``manipulator.hand_error``, applied in the hand frame): |t|_max + θ_max·r
  with r about the hand origin (taken at the park configuration: wrist bodies turn about the
  wrist centre, which changes r by centimetres and the margin by θ_max·Δr < 1 mm), a ball
  (``SweepOptions.margins``);
* the arm's own bodies and the held pin move together under one hand error, so a pair of them
  keeps the clearance only (``SweepOptions.rigid``).

Seed_4_8 gives BOX a ball bound of 1.43 cm (0.3 in, 0.2 in, 5° at its corners' 5.85 cm lever
about ẑ; 1.68 cm at the 8.8 cm of its bounding ball), the fingers 0.29 cm and the wrist
0.5–0.64 cm: without them the planner's program for seed_4_8 at the arm's first base,
(20, 80) cm, left the box 1 mm and hit it with wrist_body in 56 of 300 sampled worlds.

A candidate whose gross motion comes closer than that to a solid is rejected, the bodies named,
with the closest distance the pair reaches along the motion and the distance it needs.

The fine motions at the target hole (:mod:`synth.strategies.fine`) use :meth:`fine` and
:meth:`letting_go`: there the hand follows the target part (the pin touches it or sits in
it), so the part and the hand keep the clearance only, the other solids their own margins, and
the pin may touch the part (its tip enters the hole or lands on the surface). Once the pin is
seated the hand follows the hole's place but not the part's turn: the let-go and the get-clear
are swept again with the part turned about the seat to each extreme of its rotation error
(:meth:`GrossMotionCheck.seat_turns`), and the hand stands off the pin by the grip
(:meth:`GrossMotionCheck.seated_options`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.models.arm import (
    FINGERS,
    Arm,
    CollisionScene,
    HeldObject,
    Obstacle,
    SweepOptions,
    SweepResult,
    swept_path,
)
from synth.models.arm.bodies import bounding_radius, hull_points
from synth.models.arm.sweep import Displacement, LinkDisplacement
from synth.models.graph import AttributeGraph
from synth.models.spec import WORLD, HoleShape
from synth.models.uncertainty import Uncertainty
from synth.models.workcell import TABLE, NominalPoses, PinModel, WorkcellModel
from synth.strategies.records import Grasp

__all__ = [
    "GrossMotionCheck",
    "SeatTurn",
    "in_hole_displacement",
    "link_displacement",
    "link_margin",
    "solid_displacement",
    "solid_margin",
]


def link_margin(block: Uncertainty, radius: float) -> float:
    """|t|_max + θ_max·r [m]: how far a point within ``radius`` of a link's origin can move."""
    bounds = block.bounds()

    def extreme(name: str) -> float:
        b = bounds.get(name)
        return 0.0 if b is None else max(abs(b.lo), abs(b.hi))

    translation = math.sqrt(sum(extreme(n) ** 2 for n in ("x", "y", "z")))
    angle = sum(extreme(n) for n in ("rx", "ry", "rz"))
    return translation + angle * radius


def link_displacement(
    block: Uncertainty,
    rotation: NDArray[np.float64],
    radius: float,
    points: NDArray[np.float64] | None = None,
) -> LinkDisplacement:
    """The directional displacement bound of a link's error block (link frame ``rotation``).

    ``points``: the solid's hull vertices in the link frame [m], when it has them.
    """
    bounds = block.bounds()

    def extreme(name: str) -> float:
        b = bounds.get(name)
        return 0.0 if b is None else max(abs(b.lo), abs(b.hi))

    return LinkDisplacement(
        rotation=np.array(rotation, dtype=float),
        translation=np.array([extreme(n) for n in ("x", "y", "z")]),
        angles=np.array([extreme(n) for n in ("rx", "ry", "rz")]),
        radius=radius,
        points=points,
    )


def solid_displacement(
    graph: AttributeGraph, frame: str, geometry: coal.CollisionGeometry
) -> Displacement:
    """How far any point of ``frame``'s solid may be from its believed place, per direction.

    One :func:`link_displacement` per uncertain link L on the way from the world to ``frame``
    (itself included), at the levers about L's axes of the solid's hull vertices, or at the
    radius about L's origin of its bounding ball (:class:`LinkDisplacement`).
    """
    links = _uncertain_links(graph, frame)
    return Displacement(
        tuple(_moved_by(graph, name, frame, geometry) for name in _ordered(graph, frame, links))
    )


def _ordered(graph: AttributeGraph, frame: str, links: set[str]) -> list[str]:
    """``links`` in the order they stand on the way from ``frame`` up to the world."""
    return [name for name in graph.ancestors(frame)[:-1] if name in links]


def _moved_by(
    graph: AttributeGraph, link: str, frame: str, geometry: coal.CollisionGeometry
) -> LinkDisplacement:
    """How far ``link``'s error moves ``frame``'s solid (hull levers or ball, about ``link``)."""
    block = graph.links[link].uncertainty
    assert block is not None
    world_link = graph.world_from(link)
    link_from_solid = world_link.actInv(graph.world_from(frame))
    radius = bounding_radius(geometry, link_from_solid)
    points = hull_points(geometry, link_from_solid)
    return link_displacement(block, world_link.rotation, radius, points)


def in_hole_displacement(
    graph: AttributeGraph,
    frame: str,
    geometry: coal.CollisionGeometry,
    hole_frame: str,
    pin_box: NDArray[np.float64],
) -> Displacement:
    """How far a point of ``frame``'s solid may be from its believed place against a guided pin.

    Per direction, against a pin in the bore of the hole ``hole_frame``, which holds it on its
    axis at the depth where the commanded pin end projects onto that axis
    (:mod:`synth.replay.guided`); ``pin_box`` (8, 3) [m] are the corners of a box holding the
    pin there, hole frame. Per uncertain link L, error t + (R − I)p in L's frame:

    * L above the solid only moves it (:func:`solid_displacement`'s term);
    * L above both moves them as one rigid body but for the pin's depth, which follows the
      command: their gap keeps but for the hole's motion along its axis a, at most
      Σ_i |a·l_i|·t_i + (R − I)h's along ±a (``l_i`` L's axes, ``h`` the hole);
    * L above the hole only moves the pin across the axis by t's part across it (each of the
      hole's x, y bounded by Σ_i |x·l_i|·t_i), the command keeping its depth, and turns it
      with the bore by (R − I)p at the levers of ``pin_box``'s corners.

    A solid on the hole's part (a step of it, a block on it) thus keeps only the hole's error
    along the axis: a block standing 0.23 cm of plate beyond the bore was charged the plate's
    ±0.05 in, ±0.5° and every insertion refused.
    """
    solid_links = _uncertain_links(graph, frame)
    hole_links = _uncertain_links(graph, hole_frame)
    world_hole = graph.world_from(hole_frame)
    hole_axes = world_hole.rotation
    links = [
        _moved_by(graph, name, frame, geometry)
        for name in _ordered(graph, frame, solid_links - hole_links)
    ]
    along = 0.0
    for name in _ordered(graph, hole_frame, hole_links):
        block = graph.links[name].uncertainty
        assert block is not None
        world_link = graph.world_from(name)
        link_from_hole = world_link.actInv(world_hole)
        moved = link_displacement(block, world_link.rotation, 0.0)
        across = np.abs(hole_axes.T @ world_link.rotation) @ moved.translation  # hole frame
        if name in solid_links:
            hole = link_from_hole.translation
            at_hole = replace(moved, radius=float(np.linalg.norm(hole)), points=hole[None, :])
            axis = hole_axes[:, 2]
            along += max(at_hole.support(axis), at_hole.support(-axis))
            continue
        links.append(
            LinkDisplacement(hole_axes, across * np.array([1.0, 1.0, 0.0]), np.zeros(3), 0.0)
        )
        corners = np.array([link_from_hole.act(c) for c in pin_box])
        radius = float(np.max(np.linalg.norm(corners, axis=1)))
        links.append(replace(moved, translation=np.zeros(3), radius=radius, points=corners))
    if along > 0.0:
        links.append(LinkDisplacement(hole_axes, np.array([0.0, 0.0, along]), np.zeros(3), 0.0))
    return Displacement(tuple(links))


def _uncertain_links(graph: AttributeGraph, frame: str) -> set[str]:
    """The links on the way from the world to ``frame`` (itself included) with an error block."""
    return {
        name
        for name in graph.ancestors(frame)[:-1]
        if (block := graph.links[name].uncertainty) is not None and block.bounds()
    }


def solid_margin(graph: AttributeGraph, frame: str, geometry: coal.CollisionGeometry) -> float:
    """How far [m] any point of ``frame``'s solid may be from its believed place (any direction).

    The ball bound of :func:`solid_displacement`: Σ_L |t|_max + θ_max·r_L.
    """
    return solid_displacement(graph, frame, geometry).bound()


def _pair_distance(scene: CollisionScene, q: NDArray[np.float64], k: int) -> float:
    """Distance [m] of the scene's pair ``k`` at ``q`` (that pair only)."""
    pin.framesForwardKinematics(scene.model, scene.data, q)
    pin.updateGeometryPlacements(scene.model, scene.data, scene.geometry_model, scene.geometry_data)
    result = pin.computeDistance(scene.geometry_model, scene.geometry_data, k)
    return float(result.min_distance)


CLOSEST_SAMPLES = 24
"""Samples of the rest of the segment where a sweep stopped, for the closest distance [1]."""


@dataclass(frozen=True, eq=False)
class SeatTurn:
    """A part turned under the hand about the seat: ``solids`` (AL names) moved by ``motion``."""

    words: str
    motion: pin.SE3
    solids: frozenset[str]


@dataclass(eq=False)
class GrossMotionCheck:
    """Sweeps of gross motions in the believed workcell (see the module docstring).

    ``solids`` are the static solids at their nominal poses; ``carried`` the pin to be moved,
    ``pin_standing`` the same pin as an obstacle in its start hole. ``empty`` and ``carrying``
    are the sweep options (margins) of the two kinds of scene: the pin is an obstacle with its
    pose error in the first, a body of the hand with the hand's error in the second. Scenes are
    cached by finger opening and grasp. Not thread-safe (Coal data), like
    :class:`CollisionScene`.
    """

    arm: Arm
    solids: tuple[Obstacle, ...]
    carried: PinModel
    pin_standing: Obstacle
    empty: SweepOptions = field(default_factory=SweepOptions)
    carrying: SweepOptions = field(default_factory=SweepOptions)
    fine_motion: SweepOptions = field(default_factory=SweepOptions)
    solid_frames: dict[str, str] = field(default_factory=dict)
    hand_error: Uncertainty | None = None
    wrist_radii: dict[str, float] = field(default_factory=dict)
    _scenes: dict[tuple[object, ...], CollisionScene] = field(default_factory=dict)
    _apart: dict[tuple[object, ...], tuple[CollisionScene, CollisionScene]] = field(
        default_factory=dict
    )

    @staticmethod
    def of(
        arm: Arm,
        graph: AttributeGraph,
        pin_frame: str,
        hand_error: Uncertainty | None,
        q_reference: NDArray[np.float64],
    ) -> GrossMotionCheck:
        """The nominal workcell of the task with every body's uncertainty margin.

        ``hand_error`` is the arm's positioning error block; ``q_reference`` the configuration
        at which the moving bodies' distances from the hand are measured (the park).
        """
        model = WorkcellModel(graph, [arm.world_from_base.translation])
        workcell = model.place(NominalPoses(graph))
        carried = model.pins[pin_frame]
        pin_standing = model.pin_obstacle(pin_frame, graph.world_from(pin_frame))
        frames = {graph.al_names[name]: name for name in graph.nodes}
        solids: dict[str, Displacement] = {}
        solid_frames: dict[str, str] = {}
        # Every other pin is a solid where it stands (in its rack, or seated by an earlier step
        # of a sequence), with its own uncertainty's margin like the parts.
        others = [
            model.pin_obstacle(frame, graph.world_from(frame))
            for frame in model.pins
            if frame != pin_frame
        ]
        obstacles = (*workcell.obstacles, *others)
        for obstacle in obstacles:
            frame = frames.get(obstacle.name)
            if frame is not None:
                solid_frames[obstacle.name] = frame
                solids[obstacle.name] = solid_displacement(graph, frame, obstacle.geometry)
        moving: dict[str, float] = {}  # the arm's bodies near the hand, and the held pin
        radii: dict[str, float] = {}  # the wrist links' balls about the hand's origin
        if hand_error is not None:
            probe = CollisionScene(
                arm,
                held=HeldObject(carried.name, carried.geometry, pin.SE3.Identity()),
                opening=min(carried.shape.diameter, arm.hand.max_opening),
            )
            wrist = arm.model.njoints - 3  # the last three joints carry the wrist and hand
            hand = arm.forward(q_reference)
            for body in probe.bodies:
                if body.role in ("hand", "held") or body.joint >= wrist:
                    placed = hand.actInv(probe.body_pose(q_reference, body.name))
                    radius = bounding_radius(body.geometry, placed)
                    moving[body.name] = link_margin(hand_error, radius)
                    if body.role not in ("hand", "held"):
                        radii[body.name] = radius
        standing = solid_displacement(graph, pin_frame, pin_standing.geometry)
        arm_only = {name: m for name, m in moving.items() if name != carried.name}
        rigid = frozenset([*(b.name for b in arm.bodies), carried.name])
        return GrossMotionCheck(
            arm,
            obstacles,
            carried,
            pin_standing,
            empty=SweepOptions(
                margins=arm_only,
                displacements={**solids, carried.name: standing},
                rigid=rigid - {carried.name},
            ),
            carrying=SweepOptions(margins=moving, displacements=solids, rigid=rigid),
            fine_motion=SweepOptions(displacements=solids, rigid=rigid),
            solid_frames=solid_frames,
            hand_error=hand_error,
            wrist_radii=radii,
        )

    def part_of(self, graph: AttributeGraph, frame: str) -> str | None:
        """The solid (AL name) ``frame`` belongs to: itself or its nearest ancestor with one."""
        by_frame = {f: name for name, f in self.solid_frames.items()}
        for name in graph.ancestors(frame):
            if name in by_frame:
                return by_frame[name]
        return None

    def fine_options(
        self, part: str | None, seated_hand: NDArray[np.float64] | None = None
    ) -> SweepOptions:
        """Fine motions at ``part``: the part without a margin (the hand follows it).

        The hand follows the pin, which the hole holds, but the pin sits in the hand where the
        hand closed on it: off by the hand's positioning error at the pickup, less what
        ``CENTER`` takes out along the fingers' closing axis (x). So the hand stands off its
        believed seat by up to that error's y and z tolerances and its turns, in its own frame
        (``seated_hand``: its world rotation at the seat): each wrist link gets that directional
        bound (:func:`link_displacement` at its ball about the hand's origin). A wrist link that
        comes within the clearance is a collision (a UR5 holding the pin sideways, γ = 100°:
        wrist_3_link 0.3 cm above the box's face in the plan came within 0.08–0.10 cm of it in
        1 % of the replay's worlds); the fingers and the palm touching are felt by the wrist's
        sensor, and keep the clearance only. Without ``seated_hand``, none.
        """
        displacements = {k: v for k, v in self.fine_motion.displacements.items() if k != part}
        grip = None if seated_hand is None else self._grip(seated_hand)
        if grip is not None:
            for name, radius in self.wrist_radii.items():
                displacements[name] = Displacement((replace(grip, radius=radius),))
        return SweepOptions(displacements=displacements, rigid=self.fine_motion.rigid)

    def _grip(self, seated_hand: NDArray[np.float64]) -> LinkDisplacement | None:
        """The pin's place in the hand: the pickup's hand error less CENTER's x (hand frame)."""
        if self.hand_error is None:
            return None
        grip = link_displacement(self.hand_error, seated_hand, 0.0)
        return replace(grip, translation=grip.translation * np.array([0.0, 1.0, 1.0]))

    def seated_options(
        self,
        graph: AttributeGraph,
        part: str | None,
        seated_hand: pin.SE3,
        seat: LinkDisplacement,
        scene: CollisionScene,
        q_seated: NDArray[np.float64],
    ) -> SweepOptions:
        """:meth:`fine_options` once the hole holds the pin: the hand where the hole truly is.

        The hand stops where the search found the true hole, displaced from its believed seat
        by up to ``seat`` (the hole's world error,
        :func:`synth.strategies.fine.seated_hand_displacement`) and by the grip: the pin sits
        in the hand off where the program believes by the pickup's hand error E less what
        CENTER takes out along the fingers (hand frame), so the hand is at hole ∘ E, off by
        E's shift and by E's turn about the hand's origin. Split along the pair:

        * every solid stands off the hand by E's shift (y, z in the hand's frame), the part
          itself too: the let-go's palm 0.4 cm below a plate's face beside its corner, the
          plate turned 1.8° about the seat, hit it in 2 % of the worlds at the turn's edge
          (a 3 mm pin held at γ = 100°) when the part kept the clearance only;
        * the palm and fingers of ``scene`` (the let-go's, at ``q_seated``) turn with E about
          the hand's origin, at their hull vertices' levers (charged at the ball about the
          hand's origin, with the shift on the palm too, a Panda's palm was asked 0.96 cm
          and its tasks refused); the wrist links at their balls' (:meth:`fine_options`);
        * a solid that does not move with the part also stands off by ``seat``: a block
          2.25 cm beyond the box's edge, 8 cm tall, was hit by the fingers opening at a seat
          up to 0.76 cm nearer it than believed in 0.5–2 % of the replay's worlds. A solid
          that shares an uncertain link with the part (what stands on it, a fixture that
          holds it) moves with the hole and keeps its own margin only.

        Each term is on one side of a pair, so no pair counts E twice.
        """
        options = self.fine_options(part, seated_hand.rotation)
        part_frame = None if part is None else self.solid_frames.get(part)
        shared = set() if part_frame is None else _uncertain_links(graph, part_frame)
        displacements = dict(options.displacements)
        grip = self._grip(seated_hand.rotation)
        shift = () if grip is None else (replace(grip, angles=np.zeros(3)),)
        for obstacle in self.solids:
            name = obstacle.name
            frame = self.solid_frames.get(name)
            moves_with_part = name == part or (
                frame is not None and bool(shared & _uncertain_links(graph, frame))
            )
            own = displacements.get(name)
            extra = shift if moves_with_part else (seat, *shift)
            links = (*(() if own is None else own.links), *extra)
            if links:
                displacements[name] = Displacement(links)
        if grip is not None:
            turn = replace(grip, translation=np.zeros(3))
            for name, radius in self.wrist_radii.items():
                displacements[name] = Displacement((replace(turn, radius=radius),))
            for body in scene.bodies:
                if body.role == "hand":
                    placed = seated_hand.actInv(scene.body_pose(q_seated, body.name))
                    displacements[body.name] = Displacement(
                        (
                            replace(
                                turn,
                                radius=bounding_radius(body.geometry, placed),
                                points=hull_points(body.geometry, placed),
                            ),
                        )
                    )
        return replace(options, displacements=displacements)

    def support_of(self, graph: AttributeGraph, part: str) -> str:
        """The solid ``part`` stands on: its nearest ancestor's solid, else the table."""
        frame = self.solid_frames.get(part)
        below = None if frame is None or frame == WORLD else graph.parent(frame)
        above = None if below is None or below == WORLD else self.part_of(graph, below)
        return TABLE if above is None else above

    def fine(self, grasp: Grasp, part: str | None, bottom: str | None = None) -> CollisionScene:
        """The arm holding the pin by ``grasp`` near the target ``part`` (the pin may touch it).

        ``bottom``: a solid the pin may touch as well, the one a hole through ``part`` opens
        onto (:meth:`support_of`), where the seated pin rests.
        """
        holding = self.holding(grasp)
        key: tuple[object, ...] = ("fine", part, bottom, id(holding))
        scene = self._scenes.get(key)
        if scene is None:
            allowed = [*holding.allowed]
            for touched in (part, bottom):
                if touched is not None:
                    allowed.append(frozenset((self.carried.name, touched)))
            scene = holding.with_held(holding.held, allowed)
            self._scenes[key] = scene
        return scene

    def held_apart(
        self, grasp: Grasp, part: str | None, bottom: str | None = None
    ) -> tuple[CollisionScene, CollisionScene]:
        """:meth:`fine`'s pairs in two scenes, to be swept with different margins.

        The arm's bodies' (the held pin's pairs allowed) and the held pin's (every other pair
        allowed).
        """
        scene = self.fine(grasp, part, bottom)
        key: tuple[object, ...] = ("held apart", id(scene))
        apart = self._apart.get(key)
        if apart is None:
            held = self.carried.name
            pin_pairs = [p for p in scene.pairs if held in p]
            arm_pairs = [p for p in scene.pairs if held not in p]
            apart = (
                scene.with_held(scene.held, [*scene.allowed, *pin_pairs]),
                scene.with_held(scene.held, [*scene.allowed, *arm_pairs]),
            )
            self._apart[key] = apart
        return apart

    def in_hole_options(
        self, graph: AttributeGraph, hole_frame: str, off_axis: LinkDisplacement
    ) -> SweepOptions:
        """Margins of the held pin's pairs while the hole guides it (its end below the face).

        Each solid keeps :func:`in_hole_displacement`, plus ``off_axis``: how far the pin on
        the planned path may be from the pin on the hole's axis at the same depth (the path's
        deviation from the axis, :func:`~synth.strategies.bow.pin_deviation`).
        """
        # the pin on the axis, its end from the mouth down to the hole's depth: within this box
        hole = graph.node(hole_frame).shape
        depth = hole.depth if isinstance(hole, HoleShape) else 0.0
        r, length = self.carried.radius, self.carried.shape.length
        pin_box = np.array(
            [[sx * r, sy * r, z] for sx in (-1, 1) for sy in (-1, 1) for z in (-depth, length)]
        )
        displacements = {}
        for obstacle in self.solids:
            frame = self.solid_frames.get(obstacle.name, WORLD)
            moved = in_hole_displacement(graph, frame, obstacle.geometry, hole_frame, pin_box)
            displacements[obstacle.name] = Displacement((*moved.links, off_axis))
        return SweepOptions(displacements=displacements, rigid=self.fine_motion.rigid)

    def letting_go(
        self,
        opening: float,
        seated: pin.SE3,
        part: str | None,
        turn: SeatTurn | None = None,
    ) -> CollisionScene:
        """The empty hand at ``opening`` with the pin seated at ``seated`` (world) in ``part``.

        ``turn``: the solids it names, and the seated pin with them, moved by its ``motion``
        (a part turned under the hand about the seat: :class:`SeatTurn`).
        """
        motion = pin.SE3.Identity() if turn is None else turn.motion
        names = frozenset() if turn is None else turn.solids
        key = (
            "let go",
            round(opening, 9),
            tuple(np.round(seated.homogeneous, 9).reshape(-1)),
            tuple(np.round(motion.homogeneous, 9).reshape(-1)),
            names,
        )
        scene = self._scenes.get(key)
        if scene is None:
            solids = tuple(
                Obstacle(o.name, o.geometry, motion * o.pose) if o.name in names else o
                for o in self.solids
            )
            standing = Obstacle(self.carried.name, self.carried.geometry, motion * seated)
            scene = CollisionScene(
                self.arm,
                (*solids, standing),
                opening=min(opening, self._max_opening),
            )
            self._scenes[key] = scene
        return scene

    def seat_turns(
        self, graph: AttributeGraph, hole_frame: str, seat: NDArray[np.float64]
    ) -> list[SeatTurn]:
        """The hole's part turned under the hand about the ``seat`` (world), to each extreme.

        A pin seated in the hole holds the hand to the hole's true place h: with L the part's
        true placement against the believed one, a point p of the part moves by L(p) − p and
        the hand by L(h) − h, which leaves p displaced from the hand by (R − I)(p − h): the
        part's rotation error R about the seat is all that is left (the hand keeps its
        commanded turn). Per uncertain link above the hole, a turn by ± each of its angle bounds
        about its own axis through h, moving every solid under the link. A box turned 5° about
        a hole 0.6 cm from its edge moves that edge about 1 mm under fingers opened over it.
        Extremes, not a certified bound, as for the displaced seats of the get-clear
        (:func:`synth.strategies.fine.seat_displacements`): the angles are small.
        """
        by_frame = self.solid_frames
        turns: list[SeatTurn] = []
        for name in graph.ancestors(hole_frame)[:-1]:  # without the world
            block = graph.links[name].uncertainty
            bounds = {} if block is None else block.bounds()
            under = frozenset(o for o, f in by_frame.items() if name in graph.ancestors(f))
            axes = graph.world_from(name).rotation
            for k, axis in enumerate(("rx", "ry", "rz")):
                if axis not in bounds:
                    continue
                for angle in (bounds[axis].lo, bounds[axis].hi):
                    if abs(angle) < 1e-12:
                        continue
                    rotation = pin.exp3(angle * axes[:, k])
                    motion = pin.SE3(rotation, seat - rotation @ seat)
                    label = graph.al_names.get(name, name)
                    words = f"{label} turned {axis} {math.degrees(angle):+.2f}° about the seat"
                    turns.append(SeatTurn(words, motion, under))
        return turns

    def options_for(self, scene: CollisionScene) -> SweepOptions:
        """The margins of ``scene``: holding the pin, or with the pin standing in the cell."""
        return self.empty if scene.held is None else self.carrying

    def empty_hand(self, opening: float) -> CollisionScene:
        """The arm with open fingers among the solids and the standing pin."""
        key: tuple[object, ...] = ("empty", round(opening, 9))
        scene = self._scenes.get(key)
        if scene is None:
            obstacles = (*self.solids, self.pin_standing)
            scene = CollisionScene(self.arm, obstacles, opening=min(opening, self._max_opening))
            self._scenes[key] = scene
        return scene

    def holding(self, grasp: Grasp) -> CollisionScene:
        """The arm holding the pin by ``grasp``, fingers closed on it."""
        hand_from_pin = grasp.pin_from_hand().inverse()
        key = ("holding", tuple(np.round(hand_from_pin.homogeneous, 9).reshape(-1)))
        scene = self._scenes.get(key)
        if scene is None:
            held = HeldObject(self.carried.name, self.carried.geometry, hand_from_pin)
            scene = CollisionScene(
                self.arm,
                self.solids,
                held=held,
                allowed=[(finger, self.carried.name) for finger in FINGERS],
                opening=min(self.carried.shape.diameter, self._max_opening),
            )
            self._scenes[key] = scene
        return scene

    @property
    def _max_opening(self) -> float:
        return self.arm.hand.max_opening

    def obstruction(
        self,
        scene: CollisionScene,
        waypoints: Sequence[NDArray[np.float64]],
        motion: str,
        options: SweepOptions | None = None,
    ) -> str | None:
        """Why the joint-space path through ``waypoints`` is not clear, or None when it is.

        The reason names the pair, the closest it comes along the motion (sampled from where
        the sweep stopped to the end of that segment) and the distance it needs there: the
        clearance plus both bodies' margins along their closest points' direction.
        """
        found = self.obstructed(scene, waypoints, motion, options)
        return None if found is None else found[0]

    def obstructed(
        self,
        scene: CollisionScene,
        waypoints: Sequence[NDArray[np.float64]],
        motion: str,
        options: SweepOptions | None = None,
    ) -> tuple[str, SweepResult] | None:
        """:meth:`obstruction`'s reason, with the sweep that found it (its pair, its stop)."""
        options = options or self.options_for(scene)
        points = [np.asarray(w, dtype=float) for w in waypoints]
        result = swept_path(scene, points, options)
        if result.free:
            return None
        pair = result.pair if result.pair is not None else ("?", "?")
        closest, q_closest = result.distance, result.q
        if pair in scene.pairs and len(points) > 1:
            k = scene.pairs.index(pair)
            i = min(int(result.s), len(points) - 2)
            for u in np.linspace(result.s - i, 1.0, CLOSEST_SAMPLES):
                q = points[i] + u * (points[i + 1] - points[i])
                d = _pair_distance(scene, q, k)
                if d < closest:
                    closest, q_closest = d, q
        a, b = pair
        if a in {o.name for o in scene.environment}:
            a, b = b, a
        required = result.required if result.required > 0 else float(options.required([pair])[0])
        x, y, z = (100.0 * float(v) for v in self.arm.forward(q_closest).translation)
        where = "touch" if closest <= 0 else f"come {100 * closest:.2f} cm apart"
        reason = (
            f"the {motion} sweeps {a} into {b} (they {where}; {100 * required:.2f} cm are "
            f"needed: {100 * options.clearance:.2f} cm clearance and their uncertainty; hand "
            f"at ({x:.2f}, {y:.2f}, {z:.2f}) cm; AL moves are joint-interpolated)"
        )
        return reason, result
