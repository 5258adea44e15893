"""The task as a program believes it: every object located by contacts at its derived pose.

What the planner plans in, the emitter declares (``--preamble``) and the replay binds the
program's names to: all three must read located objects the same way (a fixture-held box has no
typed pose, only contacts). Loading a task imports no estimator; only a task with contacts
needs the location LP of :mod:`synth.errors.locate` (seed A.1, L2938–3156), imported then.
"""

from __future__ import annotations

from synth.models.graph import AttributeGraph
from synth.models.spec import TaskSpec

__all__ = ["believed_graph"]


def believed_graph(spec: TaskSpec) -> AttributeGraph:
    """``AttributeGraph`` of ``spec``, with contact-located objects at their derived poses."""
    if not spec.contacts:
        return AttributeGraph(spec)
    from synth.errors.locate import resolve_contacts  # the LP, for contact-located objects only

    return AttributeGraph(resolve_contacts(spec))
