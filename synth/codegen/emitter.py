"""Emitters: a strategy record → program text in a robot language (AL today).

An :class:`Emitter` turns a :class:`~synth.strategies.records.PinInHoleStrategy` and the task's
:class:`~synth.models.graph.AttributeGraph` into program text. Each language has one template
set (``templates/*.<language>.j2``, :mod:`synth.codegen.environment`) and one emitter class;
:func:`emit_program` picks the emitter by name. Another language is added by writing its
templates and an emitter with the same interface (and its own view builder if its pieces
differ); nothing else changes.

:class:`ALEmitter` (seed §4.7): the view is :func:`synth.codegen.views.program_view`, the
skeleton ``program.al.j2``; the optional preamble is the world binding of
:func:`synth.codegen.binding.preamble` (frame declarations, nominal poses, affixments), so the file
runs stand-alone. Like openapi-python-client's generated code, the output must pass the next
tool: every program is parsed with :func:`synth.al.parser.parse_program` before it is
returned, and a program our parser rejects is a :class:`~synth.exceptions.CodegenError`, never
a file on disk.
"""

from __future__ import annotations

import functools
from typing import ClassVar, Protocol

from synth.al.parser import parse_program
from synth.codegen.binding import preamble as world_preamble
from synth.codegen.environment import template_environment, template_name
from synth.codegen.views import ProgramView, program_view
from synth.exceptions import ALSyntaxError, CodegenError
from synth.models.graph import AttributeGraph
from synth.strategies.records import PinInHoleStrategy

__all__ = ["ALEmitter", "Emitter", "emit_program", "emitter_for", "languages"]


class Emitter(Protocol):
    """Writes strategies as programs in one robot language."""

    language: ClassVar[str]
    """Short name (``"al"``), also the template suffix (``*.al.j2``)."""
    suffix: ClassVar[str]
    """File suffix of the programs (``".al"``)."""

    def emit(
        self, strategy: PinInHoleStrategy, graph: AttributeGraph, *, preamble: bool = False
    ) -> str:
        """The program text for ``strategy`` in ``graph``'s task, optionally stand-alone."""
        ...


class ALEmitter:
    """AL programs as Taylor's code writers printed them (seed §4.7–4.8, L2480–2844)."""

    language: ClassVar[str] = "al"
    suffix: ClassVar[str] = ".al"

    def view(self, strategy: PinInHoleStrategy, graph: AttributeGraph) -> ProgramView:
        """The view the templates render (every number and branch decided)."""
        return program_view(strategy, graph)

    def render(self, view: ProgramView) -> str:
        """The program body for ``view`` (no preamble, not yet parsed)."""
        env = template_environment(self.language)
        return env.get_template(template_name("program", self.language)).render(program=view)

    def emit(
        self, strategy: PinInHoleStrategy, graph: AttributeGraph, *, preamble: bool = False
    ) -> str:
        """The AL program; with ``preamble`` the world binding comes first.

        Raises :class:`~synth.exceptions.CodegenError` for a record that cannot be written
        (see :func:`~synth.codegen.views.program_view`) or, as an internal check, for text our
        AL parser rejects.
        """
        text = self.render(self.view(strategy, graph))
        if preamble:
            text = world_preamble(graph) + "\n" + text
        try:
            parse_program(text, filename=f"<{strategy.name or 'strategy'}{self.suffix}>")
        except ALSyntaxError as exc:
            raise CodegenError("program", f"generated AL does not parse: {exc}") from exc
        return text


_EMITTERS: dict[str, type[ALEmitter]] = {"al": ALEmitter}


def languages() -> tuple[str, ...]:
    """Names of the languages an emitter exists for."""
    return tuple(sorted(_EMITTERS))


@functools.cache
def emitter_for(language: str = "al") -> Emitter:
    """The emitter for ``language`` (one shared instance per language)."""
    cls = _EMITTERS.get(language)
    if cls is None:
        known = ", ".join(languages())
        raise CodegenError("language", f"no emitter for {language!r} (known: {known})")
    return cls()


def emit_program(
    strategy: PinInHoleStrategy,
    graph: AttributeGraph,
    *,
    language: str = "al",
    preamble: bool = False,
) -> str:
    """Program text for ``strategy`` in ``language`` (``"al"``), optionally with a preamble.

    The preamble declares the task's frames and affixments so the file runs stand-alone.
    """
    return emitter_for(language).emit(strategy, graph, preamble=preamble)
