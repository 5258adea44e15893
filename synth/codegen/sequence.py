"""An assembly sequence as one AL program: the steps' programs and the corrections between them.

Each step is emitted as a single pin-in-hole program (:func:`synth.codegen.emitter.emit_program`
with that step's believed world). After a step whose seat locates a part
(:class:`synth.errors.seat.SeatKnowledge`), the program corrects the part's frame from the
seated pin's reading (skeleton ``correct.al.j2``)::

    BEGIN
      VECTOR SEAT_OFFSET;
      SEAT_OFFSET ← INV(BOX)*DISPL(PIN1) - INV(BOX)*DISPL(BH1*TRANS(NILROTN,VECTOR(0,0,-1.71)*CM));
      BOX ← BOX*TRANS(NILROTN,VECTOR(XHAT . SEAT_OFFSET,YHAT . SEAT_OFFSET,0*CM));
    END;

i.e. the offset of the pin's end from the believed seat in the part's axes, applied along the
axes the part's block bounds (the others print ``0*CM``). The holes are affixed to the part
(the world binding), so the next step's ``BH2`` already stands where the measurement says.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from synth.al.parser import parse_program
from synth.codegen import literals as L
from synth.codegen.binding import preamble as world_preamble
from synth.codegen.environment import template_environment
from synth.codegen.literals import Fragment
from synth.errors.seat import SeatKnowledge
from synth.exceptions import ALSyntaxError, CodegenError
from synth.models.graph import AttributeGraph

__all__ = ["CorrectionView", "SequenceStep", "emit_sequence"]

_OFFSET = "SEAT_OFFSET"
_AXES = {"x": "XHAT", "y": "YHAT", "z": "ZHAT"}


@dataclass(frozen=True)
class CorrectionView:
    """The checked pieces of one correction block."""

    part: Fragment
    pin: Fragment
    hole: Fragment
    seat: Fragment
    offset: Fragment
    components: Fragment
    axes_comment: Fragment


@dataclass(frozen=True)
class SequenceStep:
    """One step for the emitter: its program body, its names, and the correction after it."""

    pin: str
    hole: str
    body: str
    knowledge: SeatKnowledge | None


@dataclass(frozen=True)
class _StepView:
    number: Fragment
    pin: Fragment
    hole: Fragment
    body: Fragment
    correction: CorrectionView | None


@dataclass(frozen=True)
class _SequenceView:
    count: Fragment
    steps: tuple[_StepView, ...]
    expected_time: Fragment


def _free_name(graph: AttributeGraph, base: str) -> str:
    used = set(graph.al_names.values())
    name, k = base, 1
    while name in used:
        k += 1
        name = f"{base}{k}"
    return name


def correction_view(knowledge: SeatKnowledge, graph: AttributeGraph) -> CorrectionView:
    """The correction block's fragments (names validated, numbers printed with units)."""
    offset = L.name(_free_name(graph, _OFFSET), field="sequence.offset")
    components = [
        Fragment(f"{_AXES[a]} . {offset}") if a in knowledge.corrected else Fragment("0*CM")
        for a in ("x", "y", "z")
    ]
    corrected = ", ".join(knowledge.corrected)
    return CorrectionView(
        part=L.name(knowledge.part_al, field="sequence.part"),
        pin=L.name(knowledge.pin_al, field="sequence.pin"),
        hole=L.name(knowledge.hole_al, field="sequence.hole"),
        seat=L.translation(np.array([0.0, 0.0, -knowledge.d_f]), field="sequence.seat"),
        offset=offset,
        components=L.join(components),
        axes_comment=L.comment(f"ALONG {corrected.upper()}"),
    )


def emit_sequence(
    steps: Sequence[SequenceStep],
    graph: AttributeGraph,
    expected_time: float,
    *,
    preamble: bool = False,
) -> str:
    """The whole sequence's AL program (parsed before it is returned, like every program)."""
    views = tuple(
        _StepView(
            Fragment(str(k)),
            L.name(s.pin, field="sequence.steps.pin"),
            L.name(s.hole, field="sequence.steps.hole"),
            Fragment(s.body.rstrip("\n")),
            # a seat that corrects no axis (the part was known better than the reading) would
            # emit PART ← PART*TRANS(NILROTN,VECTOR(0*CM,0*CM,0*CM)): no statement at all
            None
            if s.knowledge is None or not s.knowledge.corrected
            else correction_view(s.knowledge, graph),
        )
        for k, s in enumerate(steps, start=1)
    )
    view = _SequenceView(
        Fragment(str(len(views))), views, L.duration(expected_time, field="sequence.time")
    )
    env = template_environment("al")
    text = env.get_template("sequence.al.j2").render(sequence=view)
    if preamble:
        text = world_preamble(graph) + "\n" + text
    try:
        parse_program(text, filename="<sequence.al>")
    except ALSyntaxError as exc:
        raise CodegenError("program", f"generated AL does not parse: {exc}") from exc
    return text
