"""Contact assertions: how an object touches another, in the task spec and in the world base.

Seed A.1 (L2938–3156) locates a box in a fixture from symbolic relations alone::

    (contacts, bxbtm, bfl.sb, inside_of)        box bottom on the fixture floor, inside its walls
    (contacts, be9, bfls2, extent_irrelevant)   a vertical box edge against a side wall

A :class:`ContactSpec` is one such assertion, ``(contacts, a, b, kind)``: feature ``a`` of the
object being located touches feature ``b`` of the object it rests on. Features are named
``frame.feature`` (``box1.bottom``, ``box1.xneg_yneg``, ``fixture1.xpos``; see
:mod:`synth.models.features`), or a frame whose shape is a ``surface`` is a face by itself.
Kinds (the seed's qualifiers):

* ``inside_of`` — face on face; the object's vertices project inside the outline of ``b``
  (for a fixture floor: between its walls);
* ``extent_irrelevant`` — face on face, edge on face or corner on face, with no constraint on
  where along ``b`` the contact lies.

In YAML a contact is a mapping ``{a: box1.bottom, b: fixture1.floor, kind: inside_of}`` or the
seed's tuple without its predicate, ``[box1.bottom, fixture1.floor, inside_of]``. Checks that
need the frame tree (unknown frames or features, unsupported pairs) live in
:func:`synth.models.features.check_contacts`, called by the loader.
"""

from __future__ import annotations

import re
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, field_validator, model_validator

ContactKind = Literal["inside_of", "extent_irrelevant"]
CONTACT_KINDS: tuple[str, ...] = ("inside_of", "extent_irrelevant")

_REF = re.compile(r"[A-Za-z][A-Za-z0-9_-]*(\.[A-Za-z][A-Za-z0-9_]*)?", re.ASCII)


class ContactSpec(BaseModel):
    """``(contacts, a, b, kind)``: feature ``a`` of the located object touches feature ``b``."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    a: str
    b: str
    kind: ContactKind

    @model_validator(mode="before")
    @classmethod
    def _from_tuple(cls, data: Any) -> Any:
        # [box.bottom, fixture.floor, inside_of] is the seed's tuple without its predicate.
        if isinstance(data, list | tuple):
            if len(data) != 3:
                raise ValueError("a contact is [a, b, kind] or a mapping with a, b and kind")
            return {"a": data[0], "b": data[1], "kind": data[2]}
        return data

    @field_validator("a", "b")
    @classmethod
    def _ref(cls, v: str) -> str:
        if not isinstance(v, str) or _REF.fullmatch(v) is None:
            raise ValueError(
                f"{v!r} is not a feature: write FRAME.FEATURE (e.g. box.bottom) or a surface frame"
            )
        return v


__all__ = [
    "CONTACT_KINDS",
    "ContactKind",
    "ContactSpec",
]
