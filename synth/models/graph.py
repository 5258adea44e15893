"""Attribute graph of a task: shape in the nodes, structure and location on the links.

Seed ch. III (L1800–1805): "Object modeling is done by attribute graphs, in which shape
information is represented in the nodes, structural information by links, and location
information by properties of the links." Here a node is an object or a feature of a task's
frame tree; the link to its parent carries the nominal pose (a Pinocchio ``SE3``), the
affixment kind and the uncertainty block. Queries: the chain of links between two nodes, the
composed nominal pose, and features by kind.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import pinocchio as pin

from synth.exceptions import FrameLookupError
from synth.models.spec import WORLD, FrameSpec, Shape, TaskSpec
from synth.models.spec_fields import Pose
from synth.models.uncertainty import Uncertainty

_AXES = {
    "x": np.array([1.0, 0.0, 0.0]),
    "y": np.array([0.0, 1.0, 0.0]),
    "z": np.array([0.0, 0.0, 1.0]),
}


def pose_to_se3(pose: Pose) -> pin.SE3:
    """``trans(rot_1 ∘ rot_2 ∘ …, translation)`` as an ``SE3`` (AL's ``trans(rot, vec)``)."""
    rotation = np.eye(3)
    for r in pose.rotation:
        rotation = rotation @ pin.exp3(_AXES[r.axis] * r.angle)
    return pin.SE3(rotation, np.array(pose.translation, dtype=float))


@dataclass(frozen=True)
class Node:
    """An object or feature: its names, its shape attributes and its role."""

    name: str
    al_name: str
    shape: Shape | None

    @property
    def kind(self) -> str | None:
        """Shape kind (``box``, ``pin``, ``hole``, ``surface``) or None for a bare frame."""
        return None if self.shape is None else self.shape.type


@dataclass(frozen=True)
class Link:
    """The link from ``child`` to its ``parent``: nominal pose of the child in the parent."""

    child: str
    parent: str
    parent_from_child: pin.SE3
    kind: str
    uncertainty: Uncertainty | None


@dataclass(frozen=True)
class TreePath:
    """The links between two frames through their lowest common ancestor.

    ``up`` lists the links from the first frame up to the ancestor (child first); ``down`` the
    links from the ancestor down to the second frame (ancestor side first). Then
    ``from⁻¹ ∘ to = (up[-1]…up[0])⁻¹`` composed appropriately — see :meth:`AttributeGraph.relative`.
    """

    start: str
    end: str
    ancestor: str
    up: tuple[Link, ...]
    down: tuple[Link, ...]


class AttributeGraph:
    """The frame tree of one task; nodes by name, links by child, lookups by AL name too."""

    def __init__(self, spec: TaskSpec) -> None:
        self.spec = spec
        self._frames: dict[str, FrameSpec] = {f.name: f for f in spec.frames}
        self.nodes: dict[str, Node] = {
            f.name: Node(f.name, f.al_name, f.shape) for f in spec.frames
        }
        self.links: dict[str, Link] = {
            f.name: Link(f.name, f.parent, pose_to_se3(f.pose), f.kind, f.uncertainty)
            for f in spec.frames
        }
        self._by_al = {f.al_name.upper(): f.name for f in spec.frames}

    def resolve(self, name: str) -> str:
        """Canonical frame name for a frame name or an AL name (AL names fold case)."""
        if name == WORLD or name in self.nodes:
            return name
        found = self._by_al.get(name.upper())
        if found is None:
            raise FrameLookupError(name, [*self.nodes, *self._by_al])
        return found

    def node(self, name: str) -> Node:
        """The node called ``name`` (frame name or AL name)."""
        return self.nodes[self.resolve(name)]

    def parent(self, name: str) -> str:
        """Parent frame name; the world has none."""
        return self.links[self.resolve(name)].parent

    def ancestors(self, name: str) -> list[str]:
        """``name`` and its ancestors up to and including ``world``."""
        out = [self.resolve(name)]
        while out[-1] != WORLD:
            out.append(self.links[out[-1]].parent)
        return out

    def path(self, start: str, end: str) -> TreePath:
        """The links from ``start`` up to the common ancestor and down to ``end``."""
        a, b = self.ancestors(start), self.ancestors(end)
        on_b = set(b)
        ancestor = next(n for n in a if n in on_b)
        up = tuple(self.links[n] for n in a[: a.index(ancestor)])
        down = tuple(self.links[n] for n in reversed(b[: b.index(ancestor)]))
        return TreePath(a[0], b[0], ancestor, up, down)

    def world_from(self, name: str) -> pin.SE3:
        """Nominal pose of frame ``name`` in the world."""
        pose = pin.SE3.Identity()
        for n in reversed(self.ancestors(name)[:-1]):
            pose = pose * self.links[n].parent_from_child
        return pose

    def relative(self, start: str, end: str) -> pin.SE3:
        """Nominal ``start⁻¹ ∘ end``: the pose of ``end`` expressed in ``start``."""
        return self.world_from(start).inverse() * self.world_from(end)

    def features(self, kind: str) -> list[Node]:
        """Nodes whose shape is of ``kind``, in task order."""
        return [n for n in self.nodes.values() if n.kind == kind]

    def children(self, name: str) -> list[str]:
        """Direct children of ``name``, in task order."""
        parent = self.resolve(name)
        return [c for c, link in self.links.items() if link.parent == parent]

    def holes_in(self, surface: str) -> list[Node]:
        """Hole features drilled into ``surface``."""
        s = self.resolve(surface)
        return [
            n
            for n in self.features("hole")
            if n.shape is not None and n.shape.type == "hole" and n.shape.surface == s
        ]

    def owner(self, name: str) -> str:
        """The nearest ancestor (or self) that is an object (box or pin), else ``world``."""
        for n in self.ancestors(name):
            if n != WORLD and self.nodes[n].kind in ("box", "pin"):
                return n
        return WORLD

    @cached_property
    def al_names(self) -> dict[str, str]:
        """Frame name → AL name."""
        return {n: node.al_name for n, node in self.nodes.items()}
