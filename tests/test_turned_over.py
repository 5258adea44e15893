"""Turned-over pins (``direction: antiparallel``): derived parameters, AL's guard, the refusal.

The planner refuses them (synth/models/insertion.py, ``refuse_unprovable``): the replay seats a
pin only by its tip, and the emitted guard's direction is fixed when each move starts.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _paths import DATA_TASKS
from test_al_interpreter import H, Rx, ScriptedMachine, run

from synth.al.machine import ForceMonitor
from synth.cli import main
from synth.exceptions import SpecError
from synth.models.graph import AttributeGraph
from synth.models.insertion import derive
from synth.models.loader import load_task
from synth.strategies.context import plan_context

TASK = DATA_TASKS / "turned_over.yaml"


def test_head_first_lead_uses_the_shaft_radius_not_the_tip_radius() -> None:
    spec = load_task(TASK)
    assert spec.insertion is not None and spec.insertion.direction == "antiparallel"
    graph = AttributeGraph(spec)
    head_first = derive(graph, spec.insertion)
    # the flat head enters: chamfer .25 + (hole radius .32 − shaft radius .3175) = .2525 cm
    assert head_first.dr_ok == pytest.approx(0.002525)
    assert head_first.lead == pytest.approx(0.002525)
    # tip first the tapered tip (radius .13 cm) enters: .25 + (.32 − .13) = .44 cm
    tip_first = derive(graph, spec.insertion.model_copy(update={"direction": "parallel"}))
    assert tip_first.dr_ok == pytest.approx(0.0044)
    # Δθ_ok: the head's lead tilt atan(.2525 / .25) = 45.3° is capped by c/μ = .0078125/.3
    assert head_first.dtheta_ok == pytest.approx(0.0078125 / 0.3)


def test_a_force_guard_direction_is_fixed_when_its_motion_starts() -> None:
    # AL evaluates a motion's expressions before it starts (seed-al-subset §4): the guard of a
    # move that turns the pin over keeps the pin's starting z (up), not its final z (down).
    m = ScriptedMachine(lambda n, c: None, hand=H(Rx(180), (0, 0, 10)))
    run(
        """FRAME PIN; PIN ← BMANIP*TRANS(ROT(XHAT,180*DEG),VECTOR(0,0,2));
        AFFIX PIN TO BMANIP;
        MOVE PIN TO PIN*TRANS(ROT(XHAT,180*DEG),VECTOR(0,0,0))
          ON FORCE(ORIENT(PIN)*ZHAT) > 8*OZ DO STOP;
        MOVE PIN TO PIN+VECTOR(0,0,-4)
          ON FORCE(ORIENT(PIN)*ZHAT) > 8*OZ DO STOP;""",
        m,
    )
    first, second = (c.monitors[0] for c in m.commands[:2])
    assert isinstance(first, ForceMonitor) and isinstance(second, ForceMonitor)
    assert np.allclose(first.direction, (0.0, 0.0, 1.0))
    # the next move starts with the pin turned over: its guard points down, into a hole below,
    # while the hole's reaction on the pin points up — the guard can never fire
    assert np.allclose(second.direction, (0.0, 0.0, -1.0))


def test_the_planner_refuses_a_turned_over_pin_naming_the_direction() -> None:
    with pytest.raises(SpecError) as info:
        plan_context(load_task(TASK))
    assert info.value.path == "insertion.direction"
    assert "turned-over pin cannot be planned" in info.value.detail
    assert "PIN1 would enter BH1 head first" in info.value.detail


def test_synth_plan_exits_2_with_the_root_cause_first(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "p.al"
    # One worker: the task is refused before any proof, so a pool would only start interpreters.
    assert main(["plan", str(TASK), "-o", str(out), "--workers", "1"]) == 2 and not out.exists()
    first = capsys.readouterr().err.strip().splitlines()[0]
    assert "insertion.direction" in first and "turned-over pin" in first
