"""AL's variables, their block scopes and the affixment graph between frames.

The interpreter (:mod:`synth.al.interpreter`) owns one graph per program: each frame has at
most one parent, ``child = parent * parent_from_child``; a rigid link also moves the parent
when the child is assigned (S:1160–1200, S:1466–1480; seed-al-subset.md §4; the rules in full
are the interpreter's module docstring, "Affixment"). The functions here keep the graph
consistent; a request AL forbids raises :class:`FrameError`, which the interpreter reports at
the statement's line.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import pinocchio as pin

from synth.al.values import Pose, PoseKind, Value

__all__ = [
    "Affixment",
    "FrameError",
    "Link",
    "Scope",
    "Variable",
    "affix",
    "pose_kind",
    "propagate",
    "se3_of",
    "set_pose",
    "unlink",
]


class FrameError(Exception):
    """A request the affixment graph refuses (a cycle, the sensed hand moved, no value)."""


@dataclass(frozen=True, eq=False)
class Affixment:
    """A link of the affixment graph: ``child = parent * parent_from_child`` [m]."""

    child: str
    parent: str
    parent_from_child: pin.SE3
    rigid: bool


@dataclass(eq=False)
class Link:
    """A child's link to its ``parent`` (the child is ``parent * parent_from_child``)."""

    parent: Variable
    parent_from_child: pin.SE3
    rigid: bool


@dataclass(eq=False)
class Variable:
    """A declared name: its AL type, value, and place in the affixment graph."""

    name: str
    type: str
    value: Value | None = None
    hand: bool = False
    bound: bool = False
    """Defined by the world binding and not yet declared by the program itself."""
    link: Link | None = None
    children: list[Variable] = field(default_factory=list)

    @property
    def pose(self) -> Pose | None:
        """The value when it is a frame or trans."""
        return self.value if isinstance(self.value, Pose) else None


class Scope:
    """A block's names, looked up through the enclosing blocks' to the global scope."""

    def __init__(self, parent: Scope | None, name: str) -> None:
        self.parent = parent
        self.name = name
        self.variables: dict[str, Variable] = {}

    def lookup(self, name: str) -> Variable | None:
        """The innermost variable called ``name``, or None."""
        scope: Scope | None = self
        while scope is not None:
            found = scope.variables.get(name)
            if found is not None:
                return found
            scope = scope.parent
        return None


def pose_kind(variable: Variable) -> PoseKind:
    """Whether a pose stored in ``variable`` is a trans or a frame (its declared type)."""
    return "trans" if variable.type == "TRANS" else "frame"


def se3_of(value: Pose | None) -> pin.SE3:
    """The SE3 of a pose known to have a value."""
    assert value is not None
    return value.se3


def affix(child: Variable, parent: Variable, relation: pin.SE3 | None, rigid: bool) -> None:
    """``AFFIX child TO parent [RIGIDLY] [AT relation]``: link, then place the child.

    Without ``relation`` it is the current INV(parent)*child. Affixing again replaces the old
    link. Refused: the sensed hand as a child, a cycle, and no relation without both values.
    """
    if child.hand:
        raise FrameError(
            f"the hand {child.name} cannot be affixed to {parent.name}: its position is "
            f"sensed (write AFFIX {parent.name} TO {child.name})"
        )
    ancestor: Variable | None = parent
    while ancestor is not None:
        if ancestor is child:
            raise FrameError(f"affixing {child.name} to {parent.name} makes a cycle")
        ancestor = ancestor.link.parent if ancestor.link is not None else None
    if relation is None:
        if child.pose is None or parent.pose is None:
            missing = child.name if child.pose is None else parent.name
            raise FrameError(f"AFFIX without AT needs both values, and {missing} has none")
        relation = se3_of(parent.pose).inverse() * se3_of(child.pose)
    if child.link is not None:
        unlink(child)
    child.link = Link(parent, pin.SE3(relation), rigid)
    parent.children.append(child)
    if parent.pose is not None:
        child.value = Pose(se3_of(parent.pose) * relation, pose_kind(child))
        propagate(child, frozenset())


def unlink(child: Variable) -> None:
    """Cut ``child``'s link to its parent; it keeps its value."""
    link = child.link
    if link is None:
        return
    link.parent.children.remove(child)
    child.link = None


def set_pose(variable: Variable, pose: pin.SE3) -> None:
    """Assign a frame and update the graph (the interpreter's module docstring, "Affixment").

    Rigid links are followed upwards, moving each parent by the same relation; the top's
    relation to a non-rigid parent is re-derived; everything affixed below follows. Refused: a
    frame rigidly affixed to the sensed hand.
    """
    chain = [(variable, pin.SE3(pose))]
    top, top_pose = variable, chain[0][1]
    while top.link is not None and top.link.rigid:
        parent = top.link.parent
        if parent.hand:
            raise FrameError(
                f"cannot assign {variable.name}: it is rigidly affixed to the hand "
                f"{parent.name}, whose position is sensed"
            )
        top_pose = top_pose * top.link.parent_from_child.inverse()
        top = parent
        chain.append((top, top_pose))
    for v, p in chain:
        v.value = Pose(p, pose_kind(v))
    if top.link is not None and top.link.parent.pose is not None:
        top.link.parent_from_child = se3_of(top.link.parent.pose).inverse() * top_pose
    propagate(top, frozenset(id(v) for v, _ in chain))


def propagate(root: Variable, fixed: frozenset[int]) -> None:
    """Re-place every frame affixed below ``root`` (those in ``fixed``, by id, keep theirs)."""
    stack = [root]
    while stack:
        node = stack.pop()
        if node.pose is None:
            continue
        for child in node.children:
            assert child.link is not None
            if id(child) not in fixed:
                se3 = se3_of(node.pose) * child.link.parent_from_child
                child.value = Pose(se3, pose_kind(child))
            stack.append(child)
