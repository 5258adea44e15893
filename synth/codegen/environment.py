"""The one configured Jinja environment per target language (templates ``*.<language>.j2``).

Configured in the manner of openapi-python-client (style.md): the templates are package data
(``synth/codegen/templates``); ``trim_blocks``, ``lstrip_blocks`` and ``keep_trailing_newline``
so block tags leave no stray blank lines; ``StrictUndefined`` so a misspelt view field fails
instead of printing nothing; filters registered once, here; no auto-reload, no randomness, no
dictionaries iterated, so the same view always renders the same bytes.

**Only checked text is printed.** Every ``{{ … }}`` goes through :func:`_printable`, which
accepts a :class:`~synth.codegen.literals.Fragment` (made and checked by
:mod:`synth.codegen.literals`) or the output of a template macro and refuses anything else —
a raw string, a float, a ``None`` — with a :class:`~synth.exceptions.CodegenError`. Macro
output is recognised because autoescaping is on: Jinja then returns macro output as
``markupsafe.Markup``, and inserts objects that have ``__html__`` (fragments, macro output)
verbatim. Nothing else can reach the output, and since nothing else is accepted, the HTML
escaping itself never applies to AL text.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable

import jinja2
from markupsafe import Markup

from synth.codegen import literals
from synth.codegen.literals import Fragment
from synth.exceptions import CodegenError

__all__ = ["LANGUAGES", "template_environment", "template_name"]

LANGUAGES: tuple[str, ...] = ("al",)
"""Languages with a template set (``templates/*.<language>.j2``)."""

_PACKAGE = "synth.codegen"
_TEMPLATES = "templates"


def template_name(piece: str, language: str) -> str:
    """The file of ``piece`` (``program``, ``pickup``, …) in ``language``'s template set."""
    return f"{piece}.{language}.j2"


def _printable(value: object) -> Fragment | Markup:
    """Jinja ``finalize`` hook: let through checked fragments and macro output only."""
    if isinstance(value, Fragment | Markup):
        return value
    if isinstance(value, jinja2.Undefined):
        str(value)  # StrictUndefined raises UndefinedError, naming the missing field
    raise CodegenError(
        "template",
        f"a template tried to print an unchecked {type(value).__name__} ({value!r}); "
        "views must hand templates checked fragments (synth.codegen.literals)",
    )


def _join(values: Iterable[Fragment], separator: str = ",") -> Fragment:
    """``{{ items|join_al(", ") }}``: checked fragments joined by punctuation or spaces."""
    return literals.join(values, separator)


@functools.cache
def template_environment(language: str = "al") -> jinja2.Environment:
    """The configured environment for ``language`` (built once, then shared)."""
    if language not in LANGUAGES:
        known = ", ".join(LANGUAGES)
        raise CodegenError("language", f"no template set for {language!r} (known: {known})")
    env = jinja2.Environment(
        loader=jinja2.PackageLoader(_PACKAGE, _TEMPLATES),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=True,
        finalize=_printable,
        auto_reload=False,
        newline_sequence="\n",
    )
    env.filters["join_al"] = _join
    return env
