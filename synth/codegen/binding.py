"""Bind a task's world to AL names before a program runs.

A generated program uses ``PIN1``, ``BH1``, ``BPARK`` and never declares them (S:2722–2844).
They name the task's frames, and the program starts out believing the task's *nominal*
locations. :func:`bind_world` turns an :class:`~synth.models.graph.AttributeGraph` into a
:class:`WorldBinding`:

- every task frame → a global frame with its nominal world pose (``graph.world_from``);
- every link whose parent is not the world → an affixment, by the link's ``kind``:
  ``nonrigid`` → ``AFFIX child TO parent AT T``; ``rigid`` → the same ``RIGIDLY``;
  ``independent`` → no affixment (POINTY's "-" link, seed L6330: the child keeps its own
  value when the parent changes). ``T`` is the link's nominal pose, parent from child;
- the manipulator's park frame (``BPARK``) → a global frame;
- the arm's names → the hand: the manipulator's ``al_name`` and ``BMANIP``, ``BLUE``,
  ``BARM``, ``BHAND``, ``BFINGERS``. Only one arm is bound. The hand's value is sensed, so it
  comes from the machine, not from the task.

:func:`preamble` prints the same binding as AL text. Our parser reads it, and running it in an
interpreter gives the same frames and affixments as :meth:`WorldBinding.apply`. It is what
``synth replay --preamble`` shows and ``synth plan --preamble`` puts before the program; such a
program replays on the bound world, since a top-level declaration of a bound frame adopts it
(:mod:`synth.al.interpreter`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from synth.al import ast
from synth.al.interpreter import (
    HAND_NAMES,
    MAX_STATEMENTS,
    MAX_TIME,
    MAX_WALL_TIME,
    Interpreter,
)
from synth.al.machine import Machine
from synth.al.printer import format_program
from synth.models.graph import AttributeGraph, pose_to_se3
from synth.models.spec import WORLD

__all__ = [
    "BoundAffixment",
    "BoundFrame",
    "WorldBinding",
    "bind_world",
    "preamble",
]

_DIGITS = 9
"""Decimal places kept when printing centimetres and degrees (1e-9 cm, 1e-9 deg)."""
_NAMES_PER_DECLARATION = 6


@dataclass(frozen=True, eq=False)
class BoundFrame:
    """A task frame bound to an AL name, at its nominal world pose [m]."""

    al_name: str
    world_pose: pin.SE3


@dataclass(frozen=True, eq=False)
class BoundAffixment:
    """``AFFIX child TO parent [RIGIDLY] AT parent_from_child`` (translation [m])."""

    child: str
    parent: str
    parent_from_child: pin.SE3
    rigid: bool


@dataclass(frozen=True, eq=False)
class WorldBinding:
    """The believed world of a task, as AL sees it at program start."""

    task: str
    frames: tuple[BoundFrame, ...]
    """Parents before children, the park frame last."""
    affixments: tuple[BoundAffixment, ...]
    hand_names: tuple[str, ...]
    """The arm's names; the first is the manipulator's own ``al_name``."""

    def apply(self, interpreter: Interpreter) -> None:
        """Define the frames and make the affixments in ``interpreter``'s global scope."""
        for frame in self.frames:
            interpreter.define_frame(frame.al_name, frame.world_pose)
        for a in self.affixments:
            interpreter.affix(a.child, a.parent, a.parent_from_child, rigid=a.rigid)

    def interpreter(
        self,
        machine: Machine,
        *,
        max_statements: int = MAX_STATEMENTS,
        max_time: float = MAX_TIME,
        max_wall_time: float = MAX_WALL_TIME,
    ) -> Interpreter:
        """A fresh interpreter on ``machine`` with this binding applied (budgets: see it)."""
        interpreter = Interpreter(
            machine,
            hand_names=self.hand_names,
            max_statements=max_statements,
            max_time=max_time,
            max_wall_time=max_wall_time,
        )
        self.apply(interpreter)
        return interpreter


def bind_world(graph: AttributeGraph) -> WorldBinding:
    """The AL binding of ``graph``'s task (see the module docstring)."""
    names = graph.al_names
    order = sorted(graph.nodes, key=lambda n: len(graph.ancestors(n)))
    frames = [BoundFrame(names[n], graph.world_from(n)) for n in order]
    affixments = []
    for n in order:
        link = graph.links[n]
        if link.parent == WORLD or link.kind == "independent":
            continue
        affixments.append(
            BoundAffixment(
                names[n], names[link.parent], pin.SE3(link.parent_from_child), link.kind == "rigid"
            )
        )
    hand_names = HAND_NAMES
    manipulator = graph.spec.manipulator
    if manipulator is not None:
        frames.append(BoundFrame(manipulator.park.al_name, pose_to_se3(manipulator.park.pose)))
        hand_names = tuple(dict.fromkeys((manipulator.al_name.upper(), *HAND_NAMES)))
    return WorldBinding(graph.spec.name, tuple(frames), tuple(affixments), hand_names)


# --------------------------------------------------------------------------------------------
# The binding as AL text


def _number(value: float) -> ast.Expr:
    rounded = round(value, _DIGITS) + 0.0  # + 0.0 turns -0.0 into 0.0
    if rounded < 0:
        return ast.UnaryOp("-", ast.Number(-rounded))
    return ast.Number(rounded)


def _call(name: str, *args: ast.Expr) -> ast.Call:
    return ast.Call(ast.Name(name), args)


def _rotation(rotation: np.ndarray) -> ast.Expr:
    axis_angle = pin.log3(rotation)
    angle = float(np.linalg.norm(axis_angle))
    if angle < 1e-12:
        return ast.Name("NILROTN")
    axis = _call("VECTOR", *(_number(float(a)) for a in axis_angle / angle))
    degrees = ast.BinOp("*", _number(math.degrees(angle)), ast.Name("DEG"))
    return _call("ROT", axis, degrees)


def _pose(constructor: str, se3: pin.SE3) -> ast.Expr:
    centimetres = _call("VECTOR", *(_number(float(x) * 100.0) for x in se3.translation))
    vector = ast.BinOp("*", centimetres, ast.Name("CM"))
    return _call(constructor, _rotation(se3.rotation), vector)


def _comment_safe(text: str) -> str:
    return text.replace("{", "(").replace("}", ")")


def preamble(graph: AttributeGraph) -> str:
    """The world binding of ``graph`` as AL: declarations, assignments and AFFIX statements.

    Frames whose parent is the world (and ``independent`` ones) are assigned their world pose.
    Affixed frames get ``AFFIX child TO parent [RIGIDLY] AT TRANS(...)``, which also gives them
    their value. Lengths are printed in ``CM`` and angles in ``DEG``, rounded to 1e-9.
    """
    binding = bind_world(graph)
    affixed = {a.child: a for a in binding.affixments}
    names = [f.al_name for f in binding.frames]
    body: list[ast.Stmt] = []
    for i in range(0, len(names), _NAMES_PER_DECLARATION):
        chunk = names[i : i + _NAMES_PER_DECLARATION]
        body.append(ast.Declaration("FRAME", tuple(ast.Name(n) for n in chunk)))
    for frame in binding.frames:
        link = affixed.get(frame.al_name)
        if link is None:
            body.append(ast.Assign(ast.Name(frame.al_name), _pose("FRAME", frame.world_pose)))
        else:
            relation = _pose("TRANS", link.parent_from_child)
            body.append(
                ast.Affix(ast.Name(link.child), ast.Name(link.parent), relation, link.rigid)
            )
    header = (
        f"{{ World binding of task {_comment_safe(binding.task)}: nominal frames and affixments.\n"
        f"  The arm's hand, sensed: {', '.join(binding.hand_names)}. }}\n"
    )
    return header + format_program(ast.Program(tuple(body)))
