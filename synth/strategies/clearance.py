"""Gross motions clear of the workcell: the planner's swept check of the moves between sites.

The seed's code writers check the geometry of a grasp (§4.3.1, L2048–2070) and leave the path
between sites to the arm. AL moves are joint-interpolated (seed L3846), and a joint-interpolated
move of the Stanford arm swings the hand in an arc about the column, which can pass through an
object that the straight line between the two sites misses: with the seed_4_8 arm at
(20, 80) cm, the planner's move from BPARK to the rack swept finger_left through BOX, and the
replay refused the program (issue 5). So every candidate's gross motions are swept here, with
Coal and conservative advancement (:func:`synth.models.arm.swept_path`), along the straight
joint-space segments between the configurations the planner timed:

1. ``park → grasp approach``: empty hand, fingers at the approach opening (L2139); every solid
   of the workcell (:mod:`synth.models.workcell`: table, boxes, racks, fixtures) and the pin
   standing in its start hole;
2. ``departure → hole approach`` (and, for a tap, ``departure → tap via``): the pin held at the
   grasp, fingers closed on it, the same solids without the pin.

A candidate whose gross motion comes within ``SweepOptions.clearance`` (1 mm) of a solid is
rejected, the bodies named. The fine motions (approach → grasp → departure at the start hole,
approach → hole with its guarded insertion, search and tap moves) stay with the seed's geometric
conditions and with the replay, which sweeps every motion and decides every contact.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

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
    swept_path,
)
from synth.models.graph import AttributeGraph
from synth.models.workcell import NominalPoses, PinModel, WorkcellModel

__all__ = ["GrossMotionCheck"]


@dataclass(eq=False)
class GrossMotionCheck:
    """Sweeps of gross motions in the believed workcell (see the module docstring).

    ``solids`` are the static solids at their nominal poses; ``carried`` the pin to be moved,
    ``pin_standing`` the same pin as an obstacle in its start hole. Scenes are cached by finger
    opening and grasp. Not thread-safe (Coal data), like :class:`CollisionScene`.
    """

    arm: Arm
    solids: tuple[Obstacle, ...]
    carried: PinModel
    pin_standing: Obstacle
    options: SweepOptions = field(default_factory=SweepOptions)
    _scenes: dict[tuple[object, ...], CollisionScene] = field(default_factory=dict)

    @staticmethod
    def of(arm: Arm, graph: AttributeGraph, pin_frame: str) -> GrossMotionCheck:
        """Build the nominal workcell of the task (table under every frame and the arm's base)."""
        model = WorkcellModel(graph, [arm.transform_world_base.translation])
        workcell = model.place(NominalPoses(graph))
        pin_standing = model.pin_obstacle(pin_frame, graph.world_from(pin_frame))
        return GrossMotionCheck(arm, workcell.obstacles, model.pins[pin_frame], pin_standing)

    def empty_hand(self, opening: float) -> CollisionScene:
        """The arm with open fingers among the solids and the standing pin."""
        key: tuple[object, ...] = ("empty", round(opening, 9))
        scene = self._scenes.get(key)
        if scene is None:
            obstacles = (*self.solids, self.pin_standing)
            scene = CollisionScene(self.arm, obstacles, opening=min(opening, self._max_opening))
            self._scenes[key] = scene
        return scene

    def holding(self, transform_hand_pin: pin.SE3) -> CollisionScene:
        """The arm holding the pin at ``transform_hand_pin``, fingers closed on it."""
        key = ("holding", tuple(np.round(transform_hand_pin.homogeneous, 9).reshape(-1)))
        scene = self._scenes.get(key)
        if scene is None:
            held = HeldObject(self.carried.name, self.carried.geometry, transform_hand_pin)
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
        self, scene: CollisionScene, waypoints: Sequence[NDArray[np.float64]], motion: str
    ) -> str | None:
        """Why the joint-space path through ``waypoints`` is not clear, or None when it is."""
        result = swept_path(scene, list(waypoints), self.options)
        if result.free:
            return None
        a, b = result.pair if result.pair is not None else ("?", "?")
        if a in {o.name for o in scene.environment}:
            a, b = b, a
        hand = self.arm.forward(result.q).translation
        x, y, z = (100.0 * float(v) for v in hand)
        return (
            f"the {motion} sweeps {a} into {b} (within {100 * result.distance:.2f} cm, clearance "
            f"{100 * self.options.clearance:.2f} cm, hand at ({x:.2f}, {y:.2f}, {z:.2f}) cm; AL "
            "moves are joint-interpolated)"
        )
