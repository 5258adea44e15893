"""Multiple-world assertion base: one world of typed facts per hypothesis.

Taylor's AL compiler "associates a data base of assertional 'forms' with each control point in
the program graph, and uses simple simulation rules to propagate facts. The same mechanism — a
multiple world assertional data base — is used by the automatic coding procedures" (seed
L1800). The facts are the fluents of §3.5 (seed L1747–1767): where objects are, what is
attached to what, and how accurately locations are known.

Facts
-----
A fact is a frozen dataclass deriving from :class:`Fact`. Its class is its predicate, and its
``KEY`` names the fields that identify it: two facts of one class with the same key are one
*functional* fact, so asserting the second replaces the first (``At(pin="PIN1",
place="departure")`` replaces ``At(pin="PIN1", place="rack")``). The other fields are its value,
typed, so that mypy checks every reader::

    world.get(Affixed, "PIN1", "BMANIP").grasp      # a Grasp, not an untyped atom

Worlds
------
Worlds form a tree: :meth:`World.root` makes one holding the task's facts, and
:meth:`World.child` branches a hypothesis in O(1) (the seed's one child world per candidate
strategy). Worlds are immutable values: :meth:`World.with_facts` returns a new world with the
same label and parent. Storage is one persistent map (``pyrsistent``) keyed by (class, key),
shared between a world and its children until either is updated.
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import ClassVar, TypeVar

from pyrsistent import pmap
from pyrsistent.typing import PMap

__all__ = ["Fact", "MatchError", "World", "WorldDiff"]


@dataclass(frozen=True)
class Fact:
    """A situational fact; subclasses are frozen dataclasses naming their key fields in ``KEY``.

    With ``KEY = ()`` a world holds at most one fact of the class.
    """

    KEY: ClassVar[tuple[str, ...]] = ()

    @property
    def key(self) -> tuple[Hashable, ...]:
        """The values of the ``KEY`` fields: what the fact is about."""
        return tuple(getattr(self, name) for name in self.KEY)

    def __init_subclass__(cls, **kwargs: object) -> None:
        super().__init_subclass__(**kwargs)
        # Runs before @dataclass has made the fields: read the annotations of the class and its
        # bases instead.
        declared = {n for k in cls.__mro__ for n in vars(k).get("__annotations__", {})}
        if not set(cls.KEY) <= declared - {"KEY"}:
            raise TypeError(f"{cls.__name__}.KEY names fields it lacks: {cls.KEY}")


F = TypeVar("F", bound=Fact)
_Slot = tuple[type[Fact], tuple[Hashable, ...]]


class MatchError(LookupError):
    """A world lacks a fact the planner expected: a bug in the planner's own world model."""


@dataclass(frozen=True)
class WorldDiff:
    """Facts ``added`` to and ``removed`` from a base world to obtain another world."""

    added: frozenset[Fact]
    removed: frozenset[Fact]

    def __bool__(self) -> bool:
        return bool(self.added or self.removed)

    def format(self) -> str:
        """One line per fact, ``+ fact`` then ``- fact``, each group sorted by ``repr``."""
        lines = [f"+ {f!r}" for f in sorted(self.added, key=repr)]
        lines += [f"- {f!r}" for f in sorted(self.removed, key=repr)]
        return "\n".join(lines)


@dataclass(frozen=True, eq=False)
class World:
    """One world of the assertion base (seed L1800): a label, its parent and its facts."""

    label: str
    parent: World | None = None
    _facts: PMap[_Slot, Fact] = field(default_factory=pmap, repr=False)

    @classmethod
    def root(cls, facts: Iterable[Fact] = (), label: str = "root") -> World:
        """A world without parent holding ``facts`` (later ones replace earlier same-key ones)."""
        return cls(label).with_facts(*facts)

    def child(self, label: str) -> World:
        """A hypothesis branched from this world: its facts, shared until either is updated."""
        return World(label, self, self._facts)

    def with_facts(self, *facts: Fact) -> World:
        """A copy of the world with ``facts`` asserted, each replacing its class and key's fact."""
        if not facts:
            return self
        evolver = self._facts.evolver()
        for fact in facts:
            if not isinstance(fact, Fact):
                raise TypeError(f"a world holds Fact records, got {fact!r}")
            evolver[(type(fact), fact.key)] = fact
        return World(self.label, self.parent, evolver.persistent())

    def find(self, kind: type[F], *key: Hashable) -> F | None:
        """The fact of class ``kind`` about ``key``, or None."""
        found = self._facts.get((kind, key))
        assert found is None or isinstance(found, kind)
        return found

    def get(self, kind: type[F], *key: Hashable) -> F:
        """The fact of class ``kind`` about ``key``; :class:`MatchError` when the world lacks it."""
        found = self.find(kind, *key)
        if found is None:
            raise MatchError(f"world {'/'.join(self.path)!r} holds no {kind.__name__}{key!r}")
        return found

    def facts(self, kind: type[F]) -> tuple[F, ...]:
        """Every fact of class ``kind``, sorted by key."""
        found = [f for (k, _), f in self._facts.items() if k is kind and isinstance(f, kind)]
        return tuple(sorted(found, key=lambda f: repr(f.key)))

    def __iter__(self) -> Iterator[Fact]:
        return iter(self._facts.values())

    def __len__(self) -> int:
        return len(self._facts)

    def __contains__(self, fact: object) -> bool:
        return isinstance(fact, Fact) and self._facts.get((type(fact), fact.key)) == fact

    @property
    def path(self) -> tuple[str, ...]:
        """Labels from the root down to this world."""
        labels: list[str] = []
        world: World | None = self
        while world is not None:
            labels.append(world.label)
            world = world.parent
        return tuple(reversed(labels))

    def diff(self, base: World | None = None) -> WorldDiff:
        """Facts added and removed from ``base`` (default: the parent; for a root, nothing)."""
        theirs = base if base is not None else self.parent
        before = set(theirs) if theirs is not None else set()
        after = set(self)
        return WorldDiff(frozenset(after - before), frozenset(before - after))

    def __repr__(self) -> str:
        return f"<World {'/'.join(self.path)}: {len(self)} facts>"
