"""Tests of the multiple-world assertion base (seed L1800, §3.5 L1747–1767): typed facts, one
child world per hypothesis."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import pytest
from _paths import SEED_TASK
from hypothesis import given, settings
from hypothesis import strategies as st

from synth.models.world import Fact, MatchError, World


@dataclass(frozen=True)
class At(Fact):
    KEY: ClassVar[tuple[str, ...]] = ("thing",)
    thing: str
    place: str


@dataclass(frozen=True)
class Accuracy(Fact):
    KEY: ClassVar[tuple[str, ...]] = ("thing",)
    thing: str
    dx: float
    dy: float


@dataclass(frozen=True)
class Task(Fact):
    name: str


@pytest.fixture
def workcell() -> World:
    """Situational facts of the seed's pin-in-hole example (seed L1747–1767)."""
    return World.root(
        [At("BOX", "T_wb"), At("PIN1", "T_wp"), Accuracy("BOX", 0.00762, 0.00508), Task("seed")],
        label="start",
    )


def test_a_child_holds_its_parents_facts_until_it_is_updated(workcell: World) -> None:
    child = workcell.child("grasp")
    assert set(child) == set(workcell) and len(child) == 4
    assert child.parent is workcell and child.path == ("start", "grasp")
    moved = child.with_facts(At("PIN1", "departure"))
    assert moved.get(At, "PIN1").place == "departure"
    assert child.get(At, "PIN1").place == "T_wp"  # the child itself is a value: unchanged
    assert workcell.get(At, "PIN1").place == "T_wp"
    assert moved.label == "grasp" and moved.parent is workcell


def test_siblings_are_independent_hypotheses(workcell: World) -> None:
    tap = workcell.child("tap").with_facts(At("PIN1", "tap-place"))
    search = workcell.child("search").with_facts(At("PIN1", "search-start"))
    assert (tap.get(At, "PIN1").place, search.get(At, "PIN1").place) == (
        "tap-place",
        "search-start",
    )


def test_a_fact_replaces_the_one_of_its_class_and_key(workcell: World) -> None:
    world = workcell.with_facts(Accuracy("BOX", 0.001, 0.002), Accuracy("PIN1", 0.0, 0.0))
    assert world.get(Accuracy, "BOX") == Accuracy("BOX", 0.001, 0.002)
    assert len(world) == 5  # one replaced, one added
    assert world.with_facts(Task("other")).get(Task).name == "other"  # KEY = (): one per world
    assert world.facts(Accuracy) == (Accuracy("BOX", 0.001, 0.002), Accuracy("PIN1", 0.0, 0.0))
    assert At("BOX", "T_wb") in world and At("BOX", "elsewhere") not in world


def test_a_missing_fact_names_the_world_and_the_fact(workcell: World) -> None:
    assert workcell.find(At, "BH1") is None
    with pytest.raises(MatchError, match=r"world 'start/grasp' holds no At\('BH1',\)"):
        workcell.child("grasp").get(At, "BH1")


def test_diff_lists_what_a_hypothesis_assumed(workcell: World) -> None:
    hyp = workcell.child("tap").with_facts(At("PIN1", "tap-place"), Task("seed"))
    diff = hyp.diff()
    assert diff.added == {At("PIN1", "tap-place")} and diff.removed == {At("PIN1", "T_wp")}
    assert (
        diff.format() == "+ At(thing='PIN1', place='tap-place')\n- At(thing='PIN1', place='T_wp')"
    )
    assert not workcell.child("same").diff()


def test_a_key_naming_a_missing_field_is_refused_at_definition() -> None:
    with pytest.raises(TypeError, match="KEY names fields it lacks"):

        @dataclass(frozen=True)
        class Broken(Fact):
            KEY: ClassVar[tuple[str, ...]] = ("nosuch",)
            thing: str

    with pytest.raises(TypeError, match="Fact records"):
        World.root([("at", "BOX", "T_wb")])  # type: ignore[list-item]


_OPS = st.lists(
    st.tuples(
        st.integers(0, 5),  # which world of the tree so far to start from
        st.booleans(),  # branch a child first
        st.lists(st.tuples(st.sampled_from("ABC"), st.sampled_from(["x", "y", "z"])), max_size=3),
    ),
    max_size=25,
)


@settings(max_examples=150, deadline=None)
@given(_OPS)
def test_worlds_agree_with_a_dictionary_model(ops: list) -> None:
    # The independent model: each world is a plain dict thing → place, copied on every update.
    worlds = [World.root(label="r")]
    models: list[dict[str, str]] = [{}]
    for start, branch, facts in ops:
        i = start % len(worlds)
        world = worlds[i].child(f"c{len(worlds)}") if branch else worlds[i]
        model = dict(models[i])
        world = world.with_facts(*(At(t, p) for t, p in facts))
        model.update(dict(facts))
        worlds.append(world)
        models.append(model)
    for world, model in zip(worlds, models, strict=True):
        assert {f.thing: f.place for f in world.facts(At)} == model
        assert len(world) == len(model)


def test_the_planners_root_world_states_the_task() -> None:
    from synth.models.loader import load_task
    from synth.strategies.context import plan_context
    from synth.strategies.hypotheses import At as PinAt
    from synth.strategies.hypotheses import Holding, InHole

    ctx = plan_context(load_task(SEED_TASK))
    world = ctx.base_world
    # The task starts with the pin in its start hole (the rack, at depth d_i) and the hand empty.
    assert world.get(Holding, ctx.hand_al).what == "nothing"
    assert world.get(PinAt, ctx.pin_al).place == world.get(InHole, ctx.pin_al).hole
    assert world.get(InHole, ctx.pin_al).depth == pytest.approx(ctx.d_i)
