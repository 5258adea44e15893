"""Where the arm starts: a collision-free configuration at the task's park frame.

A program starts with the hand at the park frame (BPARK), empty and closed. Which of the arm's
configurations at that pose it stands in matters: the planner's first swept motion starts from
it, and the replay must start from the same one. :func:`park_configuration` is the one rule
both use:

1. every attainable inverse solution at the park frame (closed form: all branches; DLS: the
   distinct solutions of its starts);
2. those whose bodies touch nothing of the nominal workcell (table, boxes, fixtures, the
   standing pins) and not themselves, fingers closed;
3. the best by the arm's own rating (:func:`synth.models.arm.rating.solution_rating`: the
   seed's θ5 rule for the Stanford arm, the dexterity otherwise), ties in solver order.

With the base on the table, an arm's fixed base link touches it by construction; that pair is
never checked (both fixed). A fixed base link inside any other solid (a box, a fixture, a pin)
is a task error, checked first: the scene never checks fixed pairs, so nothing later would.
Every other contact disqualifies a configuration, and when none is left the error names the
contacts of each.
"""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from synth.exceptions import SpecError
from synth.models.arm import Arm, CollisionScene, Obstacle, rank_solutions
from synth.models.graph import AttributeGraph
from synth.models.workcell import TABLE, NominalPoses, WorkcellModel

FIELD = "manipulator.park"


def nominal_environment(graph: AttributeGraph, arm: Arm) -> list[Obstacle]:
    """The believed workcell's solids and standing pins (the planner's and the start's world)."""
    model = WorkcellModel(graph, [arm.world_from_base.translation])
    workcell = model.place(NominalPoses(graph))
    pins = [model.pin_obstacle(frame, graph.world_from(frame)) for frame in model.pins]
    return [*workcell.obstacles, *pins]


def base_overlaps(arm: Arm, environment: list[Obstacle]) -> list[tuple[str, str]]:
    """(fixed arm body, solid) pairs in contact, the table excepted (the base stands on it)."""
    fixed = [b for b in arm.bodies if b.joint == 0]
    out = []
    for body in fixed:
        body_pose = coal.Transform3s(body.placement.rotation, body.placement.translation)
        for obstacle in environment:
            if obstacle.name == TABLE:
                continue
            pose = coal.Transform3s(obstacle.pose.rotation, obstacle.pose.translation)
            result = coal.CollisionResult()
            coal.collide(
                body.geometry, body_pose, obstacle.geometry, pose, coal.CollisionRequest(), result
            )
            if result.isCollision():
                out.append((body.name, obstacle.name))
    return out


def park_configuration(
    arm: Arm,
    park: pin.SE3,
    environment: list[Obstacle],
    al_name: str = "BPARK",
    opening: float | None = None,
) -> NDArray[np.float64]:
    """The arm's start at ``park`` (module docstring); :class:`SpecError` naming the park.

    ``opening`` [m]: the fingers' opening of the program's first ``OPEN``, made at the park;
    the chosen configuration must be clear with the fingers opened so, or the park is refused
    (a UR5's park 12.9 cm from its column: the opening finger met the upper arm, and every
    motion was said to be obstructed). It does not choose the configuration: the replay,
    which does not know the opening, starts from the same one.
    """
    overlaps = base_overlaps(arm, environment)
    if overlaps:
        pairs = ", ".join(f"{a} inside {b}" for a, b in overlaps)
        raise SpecError("manipulator.arm.base", f"the arm's base stands in a part: {pairs}")
    solutions = arm.inverse(park)
    x, y, z = (100 * float(v) for v in park.translation)
    where = f"the park frame {al_name} at ({x:.1f}, {y:.1f}, {z:.1f}) cm"
    if not solutions:
        raise SpecError(FIELD, f"the arm has no configuration reaching {where}")
    scene = CollisionScene(arm, environment, opening=0.0)
    clear = [q for q in solutions if not scene.in_collision(q)]
    if not clear:
        touching = "; ".join(
            ", ".join(f"{a}/{b}" for a, b in scene.collisions(q)[:3]) for q in solutions[:4]
        )
        raise SpecError(
            FIELD,
            f"every one of the arm's {len(solutions)} configurations at {where} touches "
            f"something ({touching}); move the park frame or the arm's base",
        )
    q = rank_solutions(arm, clear)[0].q
    if opening is not None:
        opened = CollisionScene(arm, environment, opening=min(opening, arm.hand.max_opening))
        opened_contacts = opened.collisions(q)
        if opened_contacts:
            pairs = ", ".join(f"{a}/{b}" for a, b in opened_contacts[:3])
            raise SpecError(
                FIELD,
                f"at {where} the fingers, opened to {100 * opening:.3g} cm as the program's "
                f"first OPEN does, touch something ({pairs}); move the park frame or the "
                "arm's base",
            )
    return q
