"""Multiple-world assertion base: situational facts per program point and per hypothesis.

Taylor's AL compiler "associates a data base of assertional 'forms' with each control point in
the program graph, and uses simple simulation rules to propagate facts. The same mechanism — a
multiple world assertional data base — is used by the automatic coding procedures" (seed
L1800). The facts are the fluents of §3.5 (seed L1747–1767): where objects are, what is
attached to what, and how accurately locations are known.

Facts and patterns
------------------
A *fact* is a non-empty tuple of hashable atoms whose first atom, a ``str``, is the predicate::

    ("affixed", "PIN1", "BMANIP", "nonrigid")
    ("at", "BOX", pose_key)          # pose_key: any hashable (a name, a frozen record)
    ("accuracy", "BOX", record)      # record: e.g. a frozen dataclass of bounds

Facts are ground: no atom may be a string that looks like a variable (``"?x"``) or the
wildcard ``"_"``. Pinocchio ``SE3`` values are not hashable; store a key or a frozen record.

A *pattern* is a tuple of the same shape whose atoms may also be variables (strings starting
with ``"?"``, e.g. ``"?x"``) or wildcards (``"_"`` or ``"?_"``). A pattern matches a fact of the
same length when every constant is equal to the fact's atom, every wildcard matches anything,
and every occurrence of the same variable matches equal atoms (``("affixed", "?x", "?x")``
only matches facts whose 2nd and 3rd atoms are equal). A query yields one binding dict per
matching fact, e.g. ``{"?x": "PIN1", "?kind": "nonrigid"}``. The order of results is
unspecified (it follows hash order); sort them if output must be deterministic.

Worlds
------
Worlds form a tree. ``World.root()`` makes an empty root; ``world.child(label)`` makes, in
O(1), a child holding exactly the parent's facts at that moment. Worlds are **immutable
values**: :meth:`World.assert_`, :meth:`World.retract`, :meth:`World.set_value` and the bulk
variants return a *new* ``World`` with the same label and the same parent, and never change
``self``, its parent or its siblings. Keep the returned value::

    hyp = base.child("tap-first")
    hyp = hyp.assert_(("affixed", "PIN1", "BMANIP", "nonrigid"))
    hyp = hyp.set_value("at", "PIN1", "PIN1@hole-approach")
    hyp.diff(base)        # what the hypothesis assumed beyond ``base``

Storage is persistent (``pyrsistent``) and shared, never copied. Facts live in a two-level
tree ``PMap`` predicate → ``PMap`` shard → ``PSet`` of facts (256 shards, chosen by a mixed
``hash(fact)``); an index tree ``PMap`` shard → ``PMap`` (predicate, argument position, atom)
→ ``PSet`` of facts, sharded likewise by the key, serves pattern queries. A child shares its
parent's trees outright (``child._facts is parent._facts``) until it is updated; an update
path-copies one small map per level and shares everything else.

The shards are not decoration: a ``PMap`` keeps its buckets in one C ``PVector`` whose
garbage-collector traversal visits every element, so with a single-level map of n facts each
update costs O(n) in collector time once many worlds are alive (measured at n = 10 000 with
10 000 live worlds: 1.6 ms per update single-level, 0.23 ms sharded, 0.085 ms of which is
pyrsistent's own work).

Costs: ``child`` O(1); an update O(arity · (n/256 + 256)) small-map work; ``diff`` skips
shards that are the same object in both worlds, so against a world it shares structure with
it costs O(changed shards · n/256).
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from itertools import chain, islice
from typing import Final, cast

from pyrsistent import pmap, pset
from pyrsistent.typing import PMap, PSet

__all__ = [
    "WILDCARDS",
    "Bindings",
    "Fact",
    "MatchError",
    "Pattern",
    "World",
    "WorldDiff",
    "is_variable",
]

Fact = tuple[Hashable, ...]
"""A ground assertion: ``(predicate, atom, ...)``; predicate is a ``str``."""

Pattern = tuple[Hashable, ...]
"""A fact shape whose atoms may be variables (``"?x"``) or wildcards (``"_"``, ``"?_"``)."""

Bindings = dict[str, Hashable]
"""Variable name (with its ``?``) → the atom it matched."""

WILDCARDS: Final = frozenset({"_", "?_"})
"""Pattern atoms that match anything and bind nothing."""

_IndexKey = tuple[Hashable, int, Hashable]  # (predicate, position ≥ 1, atom)
_Tree = PMap[Hashable, PMap[Hashable, PSet[Fact]]]  # two-level map → sets of facts
_Groups = dict[Hashable, dict[Hashable, tuple[list[Fact], list[Fact]]]]  # k1 → k2 → (add, rm)

# 256 shards per level (see the module docstring), chosen by the top byte of a Fibonacci hash.
_FIBONACCI: Final = 0x9E3779B97F4A7C15  # ⌊2^64/φ⌋
_MASK64: Final = (1 << 64) - 1

_EMPTY: Final[PSet[Fact]] = pset()
_EMPTY_MAP: Final[PMap[Hashable, PSet[Fact]]] = pmap()
_EMPTY_TREE: Final[_Tree] = pmap()

# Compiled pattern entries: (kind, payload).
_CONST: Final = 0  # payload: the atom
_VAR: Final = 1  # payload: the variable name
_ANY: Final = 2  # payload: None

_CompiledPattern = tuple[tuple[int, Hashable], ...]


class MatchError(LookupError):
    """A query expected exactly one match (or one value) and found none or several.

    A planner asking :meth:`World.match_one` is stating an invariant of its own world model, so
    a failure is a bug in the caller, not a user error; it is a ``LookupError``, not a
    ``SynthError``. ``count`` is the number of matches found, capped at ``examples`` + 1 when
    there are many; ``examples`` holds up to four of the bindings.
    """

    def __init__(
        self, pattern: Pattern, world: str, count: int, examples: Sequence[Bindings]
    ) -> None:
        self.pattern = pattern
        self.world = world
        self.count = count
        self.examples = tuple(examples)
        if count == 0:
            message = f"no fact matches {pattern!r} in world {world!r}"
        else:
            shown = ", ".join(repr(b) for b in self.examples)
            more = "or more " if count > len(self.examples) else ""
            message = (
                f"{len(self.examples)} {more}facts match {pattern!r} in world {world!r}, "
                f"expected exactly one: {shown}"
            )
        super().__init__(message)

    def __str__(self) -> str:
        return str(self.args[0])


def is_variable(atom: object) -> bool:
    """Tell whether ``atom`` is a pattern variable: a ``str`` starting with ``?``, not ``?_``."""
    return isinstance(atom, str) and atom.startswith("?") and atom != "?_"


def _check_fact(fact: object) -> Fact:
    """Return ``fact`` if it is a valid ground fact; raise ``TypeError``/``ValueError`` if not."""
    if not isinstance(fact, tuple) or not fact:
        raise TypeError(f"a fact is a non-empty tuple (predicate, atom, ...), got {fact!r}")
    if not isinstance(fact[0], str):
        raise TypeError(f"a fact's predicate must be a str, got {fact[0]!r} in {fact!r}")
    try:
        hash(fact)
    except TypeError:
        for position, atom in enumerate(fact):
            if _unhashable(atom):
                raise TypeError(
                    f"atom {position} of fact {fact!r} is unhashable ({type(atom).__name__}); "
                    "store a key or a frozen record instead"
                ) from None
        raise
    for atom in fact:
        if isinstance(atom, str) and (atom.startswith("?") or atom == "_"):
            raise ValueError(
                f"facts are ground, but {fact!r} contains {atom!r}, which reads as a pattern "
                "variable or wildcard"
            )
    return fact


def _unhashable(atom: object) -> bool:
    try:
        hash(atom)
    except TypeError:
        return True
    return False


def _compile(pattern: object) -> _CompiledPattern:
    """Classify each atom of ``pattern`` as constant, variable or wildcard (validating it)."""
    if not isinstance(pattern, tuple) or not pattern:
        raise TypeError(f"a pattern is a non-empty tuple, got {pattern!r}")
    compiled: list[tuple[int, Hashable]] = []
    for position, atom in enumerate(pattern):
        if _unhashable(atom):
            raise TypeError(
                f"atom {position} of pattern {pattern!r} is unhashable ({type(atom).__name__})"
            )
        if isinstance(atom, str) and atom in WILDCARDS:
            compiled.append((_ANY, None))
        elif is_variable(atom):
            if atom == "?":
                raise ValueError(f"bare '?' in pattern {pattern!r}: name the variable ('?x')")
            compiled.append((_VAR, atom))
        else:
            compiled.append((_CONST, atom))
    if compiled[0][0] == _CONST and not isinstance(compiled[0][1], str):
        raise TypeError(f"a pattern's predicate must be a str or a variable, got {pattern!r}")
    return tuple(compiled)


def _shard(x: Hashable) -> int:
    """Shard number in [0, 255] of a fact or an index key: the top byte of a Fibonacci hash.

    Not ``hash(x) & 255``: a ``PMap`` picks its bucket from the low bits of the same hash, so
    every key of a shard would land in one bucket and lookups would become linear scans.
    """
    return ((hash(x) * _FIBONACCI) & _MASK64) >> 56


def _tree_get(tree: _Tree, k1: Hashable, k2: Hashable) -> PSet[Fact]:
    """Return the set at ``tree[k1][k2]``, empty if absent."""
    return tree.get(k1, _EMPTY_MAP).get(k2, _EMPTY)


def _group(added: Iterable[Fact], removed: Iterable[Fact]) -> tuple[_Groups, _Groups]:
    """Group facts to add and remove by (predicate, shard) and index entries by (shard, key)."""
    by_predicate: _Groups = {}
    by_key: _Groups = {}
    for slot, batch in ((0, added), (1, removed)):
        for fact in batch:
            predicate = fact[0]
            by_predicate.setdefault(predicate, {}).setdefault(_shard(fact), ([], []))[slot].append(
                fact
            )
            for position in range(1, len(fact)):
                key = (predicate, position, fact[position])
                by_key.setdefault(_shard(key), {}).setdefault(key, ([], []))[slot].append(fact)
    return by_predicate, by_key


def _tree_apply(tree: _Tree, groups: _Groups) -> _Tree:
    """Apply grouped removals, then additions; drop sets and maps that become empty."""
    top = tree.evolver()
    for k1, inner in groups.items():
        mid_before = tree.get(k1, _EMPTY_MAP)
        mid = mid_before.evolver()
        for k2, (adds, removes) in inner.items():
            entry = mid_before.get(k2, _EMPTY).evolver()
            for fact in removes:
                entry.remove(fact)
            for fact in adds:
                entry.add(fact)
            new_entry = entry.persistent()
            if new_entry:
                mid[k2] = new_entry
            elif k2 in mid_before:  # each k2 occurs once per group
                del mid[k2]
        new_mid = mid.persistent()
        if new_mid:
            top[k1] = new_mid
        elif k1 in tree:
            del top[k1]
    return top.persistent()


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


class World:
    """One world of the multiple-world assertion base (seed L1800); an immutable value.

    Make worlds with :meth:`root` and :meth:`child`; every update returns a new ``World`` with
    the same :attr:`label` and :attr:`parent` (see the module docstring).
    """

    __slots__ = ("_count", "_depth", "_facts", "_index", "_label", "_parent")

    def __init__(
        self, label: str, parent: World | None, facts: _Tree, index: _Tree, count: int
    ) -> None:
        """Low-level constructor; use :meth:`root` and :meth:`child` instead."""
        if not isinstance(label, str):
            raise TypeError(f"a world label is a str, got {label!r}")
        self._label = label
        self._parent = parent
        self._facts = facts
        self._index = index
        self._count: int = count
        self._depth: int = 0 if parent is None else parent._depth + 1

    # ------------------------------------------------------------------ construction

    @classmethod
    def root(cls, facts: Iterable[Fact] = (), label: str = "root") -> World:
        """Make a world without parent holding ``facts`` (one bulk update)."""
        return cls(label, None, _EMPTY_TREE, _EMPTY_TREE, 0).assert_all(facts)

    def child(self, label: str) -> World:
        """Branch a child holding this world's facts; O(1), sharing all storage with ``self``."""
        return World(label, self, self._facts, self._index, self._count)

    # ------------------------------------------------------------------ tree

    @property
    def label(self) -> str:
        """Label of the world (e.g. a program point or a hypothesis name)."""
        return self._label

    @property
    def parent(self) -> World | None:
        """The world this one was branched from with :meth:`child`; ``None`` for a root."""
        return self._parent

    @property
    def depth(self) -> int:
        """Number of ancestors (0 for a root)."""
        return self._depth

    def ancestors(self) -> tuple[World, ...]:
        """Parent, grandparent, …, root (nearest first); empty for a root."""
        out: list[World] = []
        world = self._parent
        while world is not None:
            out.append(world)
            world = world._parent
        return tuple(out)

    @property
    def path(self) -> tuple[str, ...]:
        """Labels from the root down to this world."""
        labels = [self._label] + [w._label for w in self.ancestors()]
        return tuple(reversed(labels))

    def __repr__(self) -> str:
        return f"<World {'/'.join(self.path)}: {self._count} facts>"

    # ------------------------------------------------------------------ updates

    def assert_(self, fact: Fact) -> World:
        """Return a world that also holds ``fact``; ``self`` if it already does."""
        _check_fact(fact)
        if self._has(fact):
            return self
        return self._apply([fact], [])

    def retract(self, fact: Fact, *, must_exist: bool = False) -> World:
        """Return a world without ``fact``.

        If ``fact`` is absent, return ``self`` unchanged, or raise :class:`MatchError` when
        ``must_exist`` is true.
        """
        _check_fact(fact)
        if not self._has(fact):
            if must_exist:
                raise MatchError(fact, "/".join(self.path), 0, ())
            return self
        return self._apply([], [fact])

    def assert_all(self, facts: Iterable[Fact]) -> World:
        """Return a world that also holds every fact of ``facts`` (one bulk update)."""
        new = dict.fromkeys(f for f in facts if not self._has(_check_fact(f)))
        return self._apply(list(new), [])

    def retract_all(self, facts: Iterable[Fact]) -> World:
        """Return a world without any fact of ``facts`` (absent ones are ignored)."""
        present = dict.fromkeys(f for f in facts if self._has(_check_fact(f)))
        return self._apply([], list(present))

    def retract_matching(self, pattern: Pattern) -> World:
        """Return a world without every fact matching ``pattern``."""
        compiled = _compile(pattern)
        return self._apply([], list(self._matching_facts(compiled, {})))

    def set_value(self, predicate: str, *keys_and_value: Hashable) -> World:
        """Replace the functional fact ``(predicate, *keys, old)`` by ``(predicate, *keys, value)``.

        ``keys_and_value`` is ``(*keys, value)``: the last atom is the value, the rest identify
        it, e.g. ``set_value("at", "BOX", pose_key)``. Every fact ``(predicate, *keys, _)`` is
        retracted first, so afterwards exactly one such fact holds.
        """
        if not keys_and_value:
            raise TypeError(
                "set_value needs at least the value: set_value(predicate, *keys, value)"
            )
        new = _check_fact((predicate, *keys_and_value))
        old = list(self._matching_facts(_compile((*new[:-1], "_")), {}))
        if old == [new]:
            return self
        return self._apply([new], old)

    def _apply(self, added: list[Fact], removed: list[Fact]) -> World:
        """Remove ``removed`` (present, distinct), then add ``added`` (distinct, absent after)."""
        if not added and not removed:
            return self
        by_predicate, by_key = _group(added, removed)
        return World(
            self._label,
            self._parent,
            _tree_apply(self._facts, by_predicate),
            _tree_apply(self._index, by_key),
            self._count + len(added) - len(removed),
        )

    # ------------------------------------------------------------------ queries

    def _has(self, fact: Fact) -> bool:
        return fact in _tree_get(self._facts, fact[0], _shard(fact))

    def __len__(self) -> int:
        return self._count

    def __contains__(self, fact: object) -> bool:
        """Membership of a ground fact (no pattern matching; see :meth:`holds`)."""
        if not isinstance(fact, tuple) or not fact or _unhashable(fact):
            return False
        return self._has(fact)

    def predicates(self) -> frozenset[str]:
        """Predicates with at least one fact."""
        return frozenset(cast(str, p) for p in self._facts)

    def facts(self, predicate: str | None = None) -> Iterator[Fact]:
        """All facts, or those of one predicate (unspecified order)."""
        if predicate is not None:
            return chain.from_iterable(self._facts.get(predicate, _EMPTY_MAP).values())
        return chain.from_iterable(
            chain.from_iterable(shards.values()) for shards in self._facts.values()
        )

    def holds(self, pattern: Pattern) -> bool:
        """Tell whether a ground fact is present, or a pattern has at least one match."""
        compiled = _compile(pattern)
        if all(kind == _CONST for kind, _ in compiled):
            return self._has(pattern)
        return next(self._match(compiled, {}), None) is not None

    def query(
        self, pattern: Pattern, bindings: Mapping[str, Hashable] | None = None
    ) -> Iterator[Bindings]:
        """Binding dicts, one per fact matching ``pattern`` (unspecified order).

        ``bindings`` pre-binds variables (they then act as constants and are included in every
        result). Uses the (predicate, position, atom) index of the most selective constant.
        """
        compiled = _compile(pattern)  # validate now, not at first next()
        return self._match(compiled, dict(bindings or {}))

    def query_all(
        self, patterns: Sequence[Pattern], bindings: Mapping[str, Hashable] | None = None
    ) -> Iterator[Bindings]:
        """Bindings satisfying every pattern at once (a conjunctive query, joined left to right).

        E.g. ``[("affixed", "?x", "BMANIP", "_"), ("at", "?x", "?p")]``: where is whatever the
        hand holds. Put the most selective pattern first.
        """
        compiled = [_compile(p) for p in patterns]
        return self._join(compiled, 0, dict(bindings or {}))

    def match_one(self, pattern: Pattern) -> Bindings:
        """Return the bindings of the only fact matching ``pattern``.

        Raises :class:`MatchError` if no fact or several facts match.
        """
        found = list(islice(self.query(pattern), 5))
        if len(found) != 1:
            raise MatchError(pattern, "/".join(self.path), len(found), found[:4])
        return found[0]

    def value(self, predicate: str, *keys: Hashable) -> Hashable:
        """Return the value of the functional fact ``(predicate, *keys, value)``.

        See :meth:`set_value`. Raises :class:`MatchError` if there is no such fact or several.
        """
        pattern = (*_check_fact((predicate, *keys)), "?value")
        return self.match_one(pattern)["?value"]

    def _join(
        self, compiled: list[_CompiledPattern], i: int, bindings: Bindings
    ) -> Iterator[Bindings]:
        if i == len(compiled):
            yield bindings
            return
        for extended in self._match(compiled[i], bindings):
            yield from self._join(compiled, i + 1, extended)

    def _candidates(self, resolved: _CompiledPattern) -> Iterable[Fact]:
        """Smallest stored set that contains every fact matching ``resolved``."""
        kind, predicate = resolved[0]
        if kind != _CONST:
            return self.facts()
        shards = self._facts.get(predicate)
        if shards is None:
            return ()
        best: PSet[Fact] | None = None
        for position in range(1, len(resolved)):
            kind, atom = resolved[position]
            if kind == _CONST:
                key = (predicate, position, atom)
                entry = _tree_get(self._index, _shard(key), key)
                if not entry:
                    return ()
                if best is None or len(entry) < len(best):
                    best = entry
        if best is None:
            return chain.from_iterable(shards.values())
        return best

    def _resolve(self, compiled: _CompiledPattern, bindings: Bindings) -> _CompiledPattern:
        """Turn variables already bound in ``bindings`` into constants."""
        return tuple(
            (_CONST, bindings[payload]) if kind == _VAR and payload in bindings else (kind, payload)
            for kind, payload in compiled
        )

    def _matching_facts(self, compiled: _CompiledPattern, bindings: Bindings) -> Iterator[Fact]:
        for fact, _ in self._match_pairs(compiled, bindings):
            yield fact

    def _match(self, compiled: _CompiledPattern, bindings: Bindings) -> Iterator[Bindings]:
        for _, extended in self._match_pairs(compiled, bindings):
            yield extended

    def _match_pairs(
        self, compiled: _CompiledPattern, bindings: Bindings
    ) -> Iterator[tuple[Fact, Bindings]]:
        resolved = self._resolve(compiled, bindings)
        n = len(resolved)
        for fact in self._candidates(resolved):
            if len(fact) != n:
                continue
            extended = dict(bindings)
            for atom, (kind, payload) in zip(fact, resolved, strict=True):
                if kind == _CONST:
                    if atom != payload:
                        break
                elif kind == _VAR:
                    name = cast(str, payload)
                    seen = extended.get(name, _UNBOUND)
                    if seen is _UNBOUND:
                        extended[name] = atom
                    elif seen != atom:
                        break
            else:
                yield fact, extended

    # ------------------------------------------------------------------ comparison

    def diff(self, base: World | None = None) -> WorldDiff:
        """Facts added and removed going from ``base`` to ``self``.

        ``base`` defaults to the parent (for a root, the empty world). Shards that are shared
        (the same ``PSet`` object, as after :meth:`child`) are skipped without looking inside,
        so diffing a world against a near ancestor costs O(changed shards · n/256).
        """
        if base is not None:
            base_facts = base._facts
        elif self._parent is not None:
            base_facts = self._parent._facts
        else:
            base_facts = _EMPTY_TREE
        added: set[Fact] = set()
        removed: set[Fact] = set()
        for predicate in set(self._facts) | set(base_facts):
            mine = self._facts.get(predicate, _EMPTY_MAP)
            theirs = base_facts.get(predicate, _EMPTY_MAP)
            if mine is theirs:
                continue
            for shard in set(mine) | set(theirs):
                a = mine.get(shard, _EMPTY)
                b = theirs.get(shard, _EMPTY)
                if a is not b:
                    added.update(f for f in a if f not in b)
                    removed.update(f for f in b if f not in a)
        return WorldDiff(frozenset(added), frozenset(removed))

    def same_facts(self, other: World) -> bool:
        """Tell whether both worlds hold exactly the same facts (labels and parents ignored)."""
        return self._count == other._count and not self.diff(other)


_UNBOUND: Final = object()
