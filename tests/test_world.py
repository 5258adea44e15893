"""Tests of the multiple-world assertion base (seed L1800, §3.5 L1747–1767)."""

from __future__ import annotations

import sys
import time
import tracemalloc
from collections import Counter
from dataclasses import dataclass

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from synth.models.world import MatchError, World, WorldDiff, is_variable


@dataclass(frozen=True)
class Accuracy:
    """A stand-in for an accuracy record: any frozen (hashable) record may be an atom."""

    dx: float
    dy: float


def _bindings_multiset(results):
    return Counter(frozenset(b.items()) for b in results)


@pytest.fixture
def workcell() -> World:
    """Situational facts of the seed's pin-in-hole example (seed L1747–1767)."""
    return World.root(
        [
            ("at", "BOX", "T_wb"),
            ("at", "PIN1", "T_wp"),
            ("in", "PIN1", "RACK_HOLE"),
            ("accuracy", "BOX", Accuracy(0.00762, 0.00508)),
            ("affixed", "BH1", "BOX", "rigid"),
        ],
        label="start",
    )


# ---------------------------------------------------------------- tree and inheritance


def test_child_inherits_parent_facts(workcell: World) -> None:
    child = workcell.child("grasp")
    assert set(child.facts()) == set(workcell.facts())
    assert len(child) == len(workcell) == 5
    assert child.holds(("at", "BOX", "T_wb"))
    assert child.parent is workcell
    assert child.label == "grasp"
    assert child.path == ("start", "grasp")
    assert child.depth == 1 and workcell.depth == 0


def test_assert_returns_new_world_and_keeps_label_and_parent(workcell: World) -> None:
    child = workcell.child("grasp")
    fact = ("affixed", "PIN1", "BMANIP", "nonrigid")
    grasped = child.assert_(fact)
    assert grasped is not child
    assert grasped.holds(fact)
    assert not child.holds(fact)
    assert not workcell.holds(fact)
    assert grasped.label == "grasp" and grasped.parent is workcell
    assert grasped.assert_(fact) is grasped  # asserting a present fact is a no-op


def test_retraction_in_child_is_invisible_in_parent_and_siblings(workcell: World) -> None:
    fact = ("in", "PIN1", "RACK_HOLE")
    a = workcell.child("a").retract(fact)
    b = workcell.child("b")
    assert not a.holds(fact)
    assert workcell.holds(fact)
    assert b.holds(fact)
    assert len(a) == len(workcell) - 1
    # a sibling's own update stays its own, too
    b2 = b.assert_(("clear", "BH1"))
    assert not a.holds(("clear", "BH1")) and not workcell.holds(("clear", "BH1"))
    assert b2.holds(fact)


def test_grandchild_sees_ancestor_facts_and_ancestors_are_nearest_first(workcell: World) -> None:
    a = workcell.child("a").assert_(("p", 1))
    b = a.child("b").assert_(("p", 2))
    c = b.child("c")
    assert c.holds(("p", 1)) and c.holds(("p", 2))
    assert c.ancestors() == (b, a, workcell)
    assert [w.label for w in c.ancestors()] == ["b", "a", "start"]
    assert workcell.ancestors() == ()
    assert c.path == ("start", "a", "b", "c")
    assert "start/a/b/c" in repr(c)


def test_retract_absent_fact(workcell: World) -> None:
    assert workcell.retract(("at", "NOTHING", "x")) is workcell
    with pytest.raises(MatchError, match="no fact matches"):
        workcell.retract(("at", "NOTHING", "x"), must_exist=True)


def test_bulk_assert_and_retract(workcell: World) -> None:
    w = workcell.assert_all([("p", i) for i in range(10)] + [("at", "BOX", "T_wb")])
    assert len(w) == len(workcell) + 10
    w2 = w.retract_all([("p", i) for i in range(0, 10, 2)] + [("p", 99)])
    assert sorted(f[1] for f in w2.facts("p")) == [1, 3, 5, 7, 9]
    w3 = w2.retract_matching(("p", "_"))
    assert "p" not in w3.predicates()
    assert set(w3.facts()) == set(workcell.facts())
    assert w.assert_all([]) is w


# ---------------------------------------------------------------- pattern queries


def test_query_binds_variables(workcell: World) -> None:
    w = workcell.assert_all(
        [("affixed", "PIN1", "BMANIP", "nonrigid"), ("affixed", "PIN2", "YMANIP", "rigid")]
    )
    results = list(w.query(("affixed", "?x", "BMANIP", "?kind")))
    assert results == [{"?x": "PIN1", "?kind": "nonrigid"}]
    affixed = _bindings_multiset(w.query(("affixed", "?x", "?y", "_")))
    assert affixed == _bindings_multiset(
        [
            {"?x": "PIN1", "?y": "BMANIP"},
            {"?x": "PIN2", "?y": "YMANIP"},
            {"?x": "BH1", "?y": "BOX"},
        ]
    )


def test_query_with_unhashable_or_odd_patterns_reports_clearly(workcell: World) -> None:
    with pytest.raises(TypeError, match="unhashable"):
        workcell.query(("at", ["BOX"], "?p"))
    with pytest.raises(ValueError, match="name the variable"):
        workcell.query(("at", "?", "?p"))
    with pytest.raises(TypeError, match="non-empty tuple"):
        workcell.query([])  # type: ignore[arg-type]


def test_repeated_variables_must_unify() -> None:
    w = World.root([("affixed", "A", "A"), ("affixed", "A", "B"), ("affixed", "C", "C", "D")])
    assert list(w.query(("affixed", "?x", "?x"))) == [{"?x": "A"}]
    assert list(w.query(("affixed", "?x", "?x", "?y"))) == [{"?x": "C", "?y": "D"}]
    assert list(w.query(("affixed", "?x", "?y", "?x"))) == []


def test_wildcards_match_anything_and_bind_nothing() -> None:
    w = World.root([("at", "BOX", 1), ("at", "PIN", 2), ("at", "PIN", 2, "extra")])
    assert _bindings_multiset(w.query(("at", "_", "?p"))) == _bindings_multiset(
        [{"?p": 1}, {"?p": 2}]
    )
    # two wildcards never have to agree, unlike a repeated variable
    assert len(list(w.query(("at", "?_", "?_")))) == 2
    assert list(w.query(("at", "?_", "?_"))) == [{}, {}]
    assert w.holds(("at", "PIN", "_", "_"))
    assert not w.holds(("at", "PIN", "_", "_", "_"))  # arity matters


def test_variable_predicate_and_prebound_variables() -> None:
    w = World.root([("at", "BOX", 1), ("holding", "BOX"), ("clear", "BOX", "top")])
    preds = {b["?pred"] for b in w.query(("?pred", "BOX", "_"))}
    assert preds == {"at", "clear"}
    assert list(w.query(("at", "?o", "?p"), {"?o": "BOX"})) == [{"?o": "BOX", "?p": 1}]
    assert list(w.query(("at", "?o", "?p"), {"?o": "PIN"})) == []


def test_query_all_joins_patterns(workcell: World) -> None:
    w = workcell.assert_(("affixed", "PIN1", "BMANIP", "nonrigid"))
    found = list(w.query_all([("affixed", "?x", "BMANIP", "_"), ("at", "?x", "?where")]))
    assert found == [{"?x": "PIN1", "?where": "T_wp"}]
    assert list(w.query_all([])) == [{}]
    assert list(w.query_all([("affixed", "?x", "BMANIP", "_"), ("in", "?x", "BH1")])) == []


def test_holds_and_contains(workcell: World) -> None:
    assert workcell.holds(("at", "BOX", "T_wb"))
    assert ("at", "BOX", "T_wb") in workcell
    assert ("at", "BOX", "?p") not in workcell  # ``in`` is ground membership only
    assert workcell.holds(("at", "BOX", "?p"))
    assert not workcell.holds(("at", "BOX", "elsewhere"))
    assert not workcell.holds(("nothing", "_"))
    assert "junk" not in workcell


def test_match_one_raises_on_none_or_many(workcell: World) -> None:
    assert workcell.match_one(("at", "BOX", "?p")) == {"?p": "T_wb"}
    with pytest.raises(MatchError, match="no fact matches") as none:
        workcell.match_one(("at", "LID", "?p"))
    assert none.value.count == 0 and none.value.pattern == ("at", "LID", "?p")
    with pytest.raises(MatchError, match="expected exactly one") as many:
        workcell.match_one(("at", "?o", "?p"))
    assert many.value.count == 2
    many_world = World.root([("p", i) for i in range(50)])
    with pytest.raises(MatchError, match="or more") as lots:
        many_world.match_one(("p", "?i"))
    assert len(lots.value.examples) == 4


def test_accuracy_records_are_atoms(workcell: World) -> None:
    record = workcell.value("accuracy", "BOX")
    assert record == Accuracy(0.00762, 0.00508)
    assert workcell.holds(("accuracy", "_", Accuracy(0.00762, 0.00508)))


# ---------------------------------------------------------------- functional facts


def test_set_value_replaces_old_value(workcell: World) -> None:
    moved = workcell.set_value("at", "BOX", "T_wb_moved")
    assert moved.value("at", "BOX") == "T_wb_moved"
    assert not moved.holds(("at", "BOX", "T_wb"))
    assert workcell.value("at", "BOX") == "T_wb"
    assert moved.value("at", "PIN1") == "T_wp"  # other keys untouched
    assert len(moved) == len(workcell)
    assert moved.set_value("at", "BOX", "T_wb_moved") is moved
    fresh = workcell.set_value("at", "LID", "T_wl")
    assert fresh.value("at", "LID") == "T_wl" and len(fresh) == len(workcell) + 1
    # a broken functional fact (two values) is repaired by set_value
    broken = workcell.assert_(("at", "BOX", "T_other"))
    with pytest.raises(MatchError):
        broken.value("at", "BOX")
    assert broken.set_value("at", "BOX", "T_wb").value("at", "BOX") == "T_wb"
    # zero-key functional facts
    w = World.root().set_value("opening", 0.02).set_value("opening", 0.03)
    assert w.value("opening") == 0.03 and len(w) == 1
    with pytest.raises(TypeError):
        w.set_value("opening")


# ---------------------------------------------------------------- validation


@pytest.mark.parametrize(
    ("fact", "error", "message"),
    [
        (("at", "?x", "p"), ValueError, "ground"),
        (("at", "_", "p"), ValueError, "ground"),
        (("at", ["BOX"], "p"), TypeError, "atom 1 .* unhashable"),
        (("at", ("BOX", {}), "p"), TypeError, "atom 1 .* unhashable"),
        ((), TypeError, "non-empty tuple"),
        (["at", "BOX"], TypeError, "non-empty tuple"),
        ((3, "BOX"), TypeError, "predicate must be a str"),
    ],
)
def test_invalid_facts_are_rejected(fact, error, message) -> None:
    with pytest.raises(error, match=message):
        World.root().assert_(fact)


def test_is_variable() -> None:
    assert is_variable("?x") and not is_variable("?_") and not is_variable("_")
    assert not is_variable("x") and not is_variable(3)


# ---------------------------------------------------------------- diff


def test_diff_shows_what_a_hypothesis_assumed(workcell: World) -> None:
    hyp = workcell.child("tap-first")
    hyp = hyp.assert_(("affixed", "PIN1", "BMANIP", "nonrigid"))
    hyp = hyp.retract(("in", "PIN1", "RACK_HOLE"))
    hyp = hyp.set_value("at", "PIN1", "T_hole_approach")
    deeper = hyp.child("search").assert_(("searched", "BH1"))
    assert hyp.diff(workcell) == WorldDiff(
        added=frozenset(
            {("affixed", "PIN1", "BMANIP", "nonrigid"), ("at", "PIN1", "T_hole_approach")}
        ),
        removed=frozenset({("in", "PIN1", "RACK_HOLE"), ("at", "PIN1", "T_wp")}),
    )
    assert hyp.diff() == hyp.diff(workcell)  # default base: the parent
    assert deeper.diff() == WorldDiff(frozenset({("searched", "BH1")}), frozenset())
    assert deeper.diff(workcell).added == hyp.diff(workcell).added | {("searched", "BH1")}
    assert workcell.diff(hyp) == WorldDiff(hyp.diff().removed, hyp.diff().added)
    assert not workcell.child("same").diff()
    assert workcell.diff() == WorldDiff(frozenset(workcell.facts()), frozenset())
    text = hyp.diff().format()
    assert text.splitlines()[0].startswith("+ ('affixed'")
    assert "- ('in', 'PIN1', 'RACK_HOLE')" in text
    rebuilt = World.root(hyp.facts(), label="elsewhere")  # no shared structure at all
    assert hyp.same_facts(rebuilt) and rebuilt.same_facts(hyp)
    assert not hyp.same_facts(workcell)


# ---------------------------------------------------------------- structural sharing


def test_children_share_storage_until_modified() -> None:
    """10 000 children of a 10 000-fact world copy nothing (counting argument, not timing)."""
    root = World.root([("at", f"OBJ{i}", f"POSE{i}") for i in range(10_000)])
    start = time.perf_counter()
    children = [root.child(f"h{i}") for i in range(10_000)]
    elapsed = time.perf_counter() - start
    assert all(c._facts is root._facts and c._index is root._index for c in children)
    assert elapsed < 1.0, elapsed
    # an update replaces only what it touches: other predicates and other shards are shared
    mixed = root.assert_all([("clear", f"H{i}") for i in range(100)])
    updated = mixed.child("u").assert_(("at", "NEW", "POSE"))
    assert updated._facts["clear"] is mixed._facts["clear"]
    assert updated._facts["at"] is not mixed._facts["at"]
    shared = sum(
        updated._facts["at"][shard] is mixed._facts["at"].get(shard)
        for shard in updated._facts["at"]
    )
    assert shared == len(updated._facts["at"]) - 1  # exactly one shard was path-copied
    assert len(updated) == len(mixed) + 1 and len(mixed) == 10_100


def test_update_memory_is_a_small_fraction_of_a_copy() -> None:
    """1 000 chained updates of a 10 000-fact world each allocate far less than one copy."""
    base = World.root([("at", f"OBJ{i}", f"POSE{i}") for i in range(10_000)])
    names = [(f"OBJ{i}", f"MOVED{i}") for i in range(1_000)]
    tracemalloc.start()
    try:
        before, _ = tracemalloc.get_traced_memory()
        world = base
        for obj, pose in names:
            world = world.child(obj).set_value("at", obj, pose)
        after, _ = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    per_world = (after - before) / len(names)
    # A copy would at least duplicate a 10 000-fact set and a 20 000-key index (containers
    # alone, not counting the facts): ≈ 1.1 MB. A persistent update copies O(1) small maps.
    copy_size = sys.getsizeof(set(base.facts())) + sys.getsizeof(dict.fromkeys(range(20_000)))
    assert per_world < copy_size / 30, (per_world, copy_size)
    assert world.value("at", "OBJ0") == "MOVED0" and base.value("at", "OBJ0") == "POSE0"
    assert len(world) == len(base) == 10_000


def test_chain_of_10000_worlds() -> None:
    """A 10 000-deep chain of worlds, one fact each: ancestors, diff and teardown stay cheap."""
    base = World.root([("at", f"OBJ{i}", f"POSE{i}") for i in range(1_000)], label="base")
    world = base
    for i in range(10_000):
        world = world.child(f"step{i}").assert_(("visited", i))
    assert world.depth == 10_000 and len(world.ancestors()) == 10_000
    assert world.ancestors()[-1] is base
    assert len(world) == 11_000
    assert world.diff() == WorldDiff(frozenset({("visited", 9_999)}), frozenset())
    assert world.diff(base).added == {("visited", i) for i in range(10_000)}
    assert len(list(world.query(("visited", "?i")))) == 10_000
    del world  # dropping a deep chain must not overflow the C stack


# ---------------------------------------------------------------- property test

_ATOMS = st.sampled_from(["a", "b", "c", 1, 2])
_FACTS = st.builds(
    lambda p, args: (p, *args), st.sampled_from(["p", "q", "r"]), st.lists(_ATOMS, max_size=3)
)
_PATTERN_ATOMS = st.one_of(_ATOMS, st.sampled_from(["?x", "?y", "_", "?_"]))
_PATTERNS = st.builds(
    lambda p, args: (p, *args),
    st.sampled_from(["p", "q", "r", "?pred"]),
    st.lists(_PATTERN_ATOMS, max_size=3),
)
_OPS = st.one_of(
    st.tuples(st.just("child"), st.integers(0, 1000)),
    st.tuples(st.just("assert"), st.integers(0, 1000), _FACTS),
    st.tuples(st.just("retract"), st.integers(0, 1000), _FACTS),
    st.tuples(st.just("set_value"), st.integers(0, 1000), _FACTS),
    st.tuples(st.just("retract_matching"), st.integers(0, 1000), _PATTERNS),
)


def _naive_match(pattern, fact):
    if len(pattern) != len(fact):
        return None
    bindings = {}
    for p, a in zip(pattern, fact, strict=True):
        if p in ("_", "?_"):
            continue
        if isinstance(p, str) and p.startswith("?"):
            if p in bindings and bindings[p] != a:
                return None
            bindings[p] = a
        elif p != a:
            return None
    return bindings


def _naive_query(model, pattern):
    return [b for f in model if (b := _naive_match(pattern, f)) is not None]


@settings(max_examples=300, deadline=None)
@given(ops=st.lists(_OPS, max_size=40), patterns=st.lists(_PATTERNS, min_size=1, max_size=5))
def test_random_branch_updates_match_a_naive_model(ops, patterns) -> None:
    """Random assert/retract/set_value on random branches ≡ a dict of plain sets."""
    worlds = [World.root(label="w0")]
    model = [set()]
    for op in ops:
        i = op[1] % len(worlds)
        if op[0] == "child":
            worlds.append(worlds[i].child(f"w{len(worlds)}"))
            model.append(set(model[i]))
        elif op[0] == "assert":
            worlds[i] = worlds[i].assert_(op[2])
            model[i].add(op[2])
        elif op[0] == "retract":
            worlds[i] = worlds[i].retract(op[2])
            model[i].discard(op[2])
        elif op[0] == "set_value":
            fact = op[2]
            if len(fact) < 2:
                continue
            worlds[i] = worlds[i].set_value(*fact)
            model[i] = {f for f in model[i] if not (len(f) == len(fact) and f[:-1] == fact[:-1])}
            model[i].add(fact)
        else:
            worlds[i] = worlds[i].retract_matching(op[2])
            model[i] = {f for f in model[i] if _naive_match(op[2], f) is None}
        for world, facts in zip(worlds, model, strict=True):
            assert set(world.facts()) == facts
            assert len(world) == len(facts)
    for world, facts in zip(worlds, model, strict=True):
        for pattern in patterns:
            assert _bindings_multiset(world.query(pattern)) == _bindings_multiset(
                _naive_query(facts, pattern)
            )
            assert world.holds(pattern) == bool(_naive_query(facts, pattern))
        parent = world.parent
        if parent is not None:
            d = world.diff(parent)
            parent_facts = set(parent.facts())
            assert d.added == facts - parent_facts
            assert d.removed == parent_facts - facts
