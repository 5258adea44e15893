"""Read one YAML document under limits: the task loader of both the CLI and the service.

The text is parsed once. libyaml's C parser (``yaml.CSafeLoader``, when PyYAML was built with
it) turns the text into events; :func:`read_yaml` composes the events into a node tree itself,
checking every limit as each event arrives, so a hostile document is refused before any large
structure exists; PyYAML's safe constructor then turns the nodes into Python values. The line of
every field path is recorded on the way (:attr:`YamlDocument.lines`), for error messages.

The limits (:class:`YamlLimits`), each refused with a :class:`~synth.exceptions.SpecError` that
names it and the line where it was crossed:

- ``max_bytes``: the text's size in UTF-8 bytes, checked before parsing;
- ``max_depth``: mapping/sequence nesting (the task schema needs about 6);
- ``max_items``: entries in one sequence or mapping;
- ``max_aliases``: ``*name`` references in the document (0: none accepted);
- ``max_nodes``: nodes of the document *as expanded*, each alias counting the whole subtree it
  repeats. This is the bound that stops a "billion laughs" document, whose few aliases expand
  exponentially.

An alias to an anchor whose node is still open (``&a [*a]``) would make a cyclic value; it is
refused. So is a key given twice in one mapping: YAML keeps the last silently, and a second
``uncertainty:`` under a frame would drop the first one's tolerances without a word. Only one
document is accepted (as ``yaml.safe_load``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import yaml
from yaml.constructor import SafeConstructor
from yaml.resolver import Resolver

from synth.exceptions import SpecError

PathKey = tuple[str | int, ...]

_Parser: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # C-accelerated when available
WITH_LIBYAML: bool = _Parser is not yaml.SafeLoader


@dataclass(frozen=True)
class YamlLimits:
    """Bounds on one YAML document (see the module docstring for what each counts)."""

    max_bytes: int = 1 << 20  # [byte] the service's default request-body limit
    max_depth: int = 32
    max_items: int = 10_000
    max_aliases: int = 100
    max_nodes: int = 100_000


DEFAULT_LIMITS = YamlLimits()

MAX_NUMBER_CHARS = 100
"""Characters of a YAML integer at most: no task needs more, and past 4 300 digits Python's
``int()`` raises a ValueError of its own (which the service would answer with a 500)."""
_INT_TAG = "tag:yaml.org,2002:int"


@dataclass(frozen=True)
class YamlDocument:
    """A parsed document: its value and the 1-based line where each field path starts."""

    data: Any
    lines: dict[PathKey, int] = field(default_factory=dict)


@dataclass
class _Open:
    """A collection being composed: its node, path, weight so far and pending mapping key."""

    node: yaml.MappingNode | yaml.SequenceNode
    path: PathKey
    anchor: str | None
    weight: int = 1  # nodes in the expanded subtree, this one included
    key: yaml.Node | None = None  # a mapping's key, waiting for its value
    keys: dict[str, int | None] = field(default_factory=dict)  # a mapping's keys: their lines


def read_yaml(
    text: str, *, source: str = "<yaml>", limits: YamlLimits = DEFAULT_LIMITS
) -> YamlDocument:
    """Parse ``text`` (one YAML document) under ``limits``; raise :class:`SpecError` if not."""
    size = len(text.encode("utf-8", "surrogatepass"))
    if size > limits.max_bytes:
        raise SpecError(
            source, f"the YAML text is {size} bytes, over the limit of {limits.max_bytes} bytes"
        )
    try:
        node, lines = _compose(text, source, limits)
        data = None if node is None else SafeConstructor().construct_document(node)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark is not None else None
        if "maximum nesting depth" in str(exc.problem):  # libyaml's own limit, 1000 levels
            raise SpecError(source, _too_deep(limits), line) from None
        raise SpecError(source, f"YAML syntax error: {exc.problem or exc}", line) from None
    except yaml.YAMLError as exc:
        raise SpecError(source, f"YAML error: {exc}") from None
    return YamlDocument(data, lines)


def format_path(loc: PathKey) -> str:
    """``('frames', 2, 'uncertainty', 'x')`` → ``'frames[2].uncertainty.x'``."""
    text = ""
    for part in loc:
        if isinstance(part, int):
            text += f"[{part}]"
        else:
            text += f".{part}" if text else str(part)
    return text


def parse_path(text: str) -> PathKey:
    """The key of a field path: ``'frames[2].pose.x'`` → ``('frames', 2, 'pose', 'x')``."""
    loc: list[str | int] = []
    for part in text.split("."):
        name, *indices = part.split("[")
        if name:
            loc.append(name)
        loc += [int(i.rstrip("]")) for i in indices if i.rstrip("]").isdigit()]
    return tuple(loc)


def line_of(loc: PathKey, lines: dict[PathKey, int]) -> int | None:
    """The YAML line of field ``loc``: the deepest prefix of the path the YAML has a node for."""
    for n in range(len(loc), -1, -1):
        if loc[:n] in lines:
            return lines[loc[:n]]
    return None


def _too_deep(limits: YamlLimits) -> str:
    return f"the YAML is nested deeper than {limits.max_depth} levels"


def _line(event: yaml.Event) -> int | None:
    mark = event.start_mark
    return None if mark is None else mark.line + 1


def _compose(text: str, source: str, limits: YamlLimits) -> tuple[yaml.Node | None, dict]:
    """Events → node tree, refusing the document as soon as it crosses a limit."""
    resolver = Resolver()
    anchors: dict[str, tuple[yaml.Node, int]] = {}  # closed anchored nodes and their weights
    open_anchors: set[str] = set()
    stack: list[_Open] = []
    lines: dict[PathKey, int] = {}
    root: yaml.Node | None = None
    documents = 0
    aliases = 0
    expanded = 0  # nodes of the document as expanded so far

    def fail(event: yaml.Event, message: str) -> None:
        raise SpecError(source, message, _line(event))

    def path_of_next(event: yaml.Event) -> PathKey:
        """The field path of the node that ``event`` starts (its parent is ``stack[-1]``)."""
        if not stack:
            return ()
        top = stack[-1]
        if isinstance(top.node, yaml.SequenceNode):
            return (*top.path, len(top.node.value))
        if top.key is None:  # this node is a key: it shares the mapping's path
            return top.path
        key = top.key.value if isinstance(top.key, yaml.ScalarNode) else str(top.key.value)
        return (*top.path, key)

    def attach(node: yaml.Node, weight: int, event: yaml.Event) -> None:
        """Add a finished node to the collection on top of the stack (or make it the root)."""
        nonlocal root, expanded
        expanded += weight
        if expanded > limits.max_nodes:
            fail(
                event,
                f"the YAML document expands to more than {limits.max_nodes} nodes"
                " (aliases repeating large parts, as in a 'billion laughs' file?)",
            )
        if not stack:
            root = node
            return
        top = stack[-1]
        top.weight += weight
        if isinstance(top.node, yaml.SequenceNode):
            if len(top.node.value) >= limits.max_items:
                fail(event, f"a YAML list longer than {limits.max_items} items")
            top.node.value.append(node)
        elif top.key is None:
            top.key = node
            if isinstance(node, yaml.ScalarNode):
                line = None if node.start_mark is None else node.start_mark.line + 1
                if node.value in top.keys and node.value != "<<":  # YAML 1.1's merge key
                    first = top.keys[node.value]
                    raise SpecError(
                        format_path((*top.path, node.value)),
                        f"the key {node.value!r} is given twice in one mapping"
                        + ("" if first is None else f" (first at line {first})")
                        + "; YAML would keep only the last",
                        line,
                    )
                top.keys[node.value] = line
                if line is not None:
                    lines.setdefault((*top.path, node.value), line)
        else:
            if len(top.node.value) >= limits.max_items:
                fail(event, f"a YAML mapping with more than {limits.max_items} entries")
            top.node.value.append((top.key, node))
            top.key = None

    for event in yaml.parse(text, Loader=_Parser):
        if isinstance(event, yaml.DocumentStartEvent):
            documents += 1
            if documents > 1:
                fail(event, "expected a single YAML document, found another one")
        elif isinstance(event, yaml.AliasEvent):
            aliases += 1
            if aliases > limits.max_aliases:
                if limits.max_aliases == 0:
                    fail(event, "YAML aliases (*name) are not accepted here")
                fail(event, f"more than {limits.max_aliases} YAML aliases (*name)")
            name = event.anchor or ""
            if name in open_anchors:
                fail(event, f"the YAML alias *{name} refers to itself (recursive alias)")
            if name not in anchors:
                fail(event, f"the YAML alias *{name} names no anchor before it")
            target, weight = anchors[name]
            _record_line(lines, path_of_next(event), event)
            attach(target, weight, event)
        elif isinstance(event, yaml.ScalarEvent):
            _record_line(lines, path_of_next(event), event)
            tag = event.tag
            if tag is None or tag == "!":
                tag = resolver.resolve(yaml.ScalarNode, event.value, event.implicit)
            if tag == _INT_TAG and len(event.value) > MAX_NUMBER_CHARS:
                # Python refuses int() of over 4300 digits with a ValueError that names no line
                raise SpecError(
                    format_path(path_of_next(event)),
                    f"a number written with {len(event.value)} characters (more than "
                    f"{MAX_NUMBER_CHARS})",
                    _line(event),
                )
            marks: tuple[Any, Any] = (event.start_mark, event.end_mark)  # libyaml's or PyYAML's
            node = yaml.ScalarNode(tag, event.value, *marks, style=event.style)
            if event.anchor is not None:
                anchors[event.anchor] = (node, 1)
            attach(node, 1, event)
        elif isinstance(event, yaml.CollectionStartEvent):
            if len(stack) >= limits.max_depth:
                fail(event, _too_deep(limits))
            path = path_of_next(event)
            _record_line(lines, path, event)
            is_list = isinstance(event, yaml.SequenceStartEvent)
            kind: Any = yaml.SequenceNode if is_list else yaml.MappingNode
            tag = event.tag
            if tag is None or tag == "!":
                tag = resolver.resolve(kind, None, event.implicit)
            collection = kind(tag, [], event.start_mark, None, flow_style=event.flow_style)
            if event.anchor is not None:
                open_anchors.add(event.anchor)
            is_key = bool(stack) and isinstance(stack[-1].node, yaml.MappingNode)
            is_key = is_key and stack[-1].key is None
            stack.append(_Open(collection, path if not is_key else (*path, "<key>"), event.anchor))
        elif isinstance(event, yaml.CollectionEndEvent):
            done = stack.pop()
            done.node.end_mark = event.end_mark
            if done.anchor is not None:
                open_anchors.discard(done.anchor)
                anchors[done.anchor] = (done.node, done.weight)
            expanded -= done.weight - 1  # its children were counted as they were attached
            attach(done.node, done.weight, event)
    return root, lines


def _record_line(lines: dict[PathKey, int], path: PathKey, event: yaml.Event) -> None:
    # The first node at a path wins: for a mapping entry that is the key, where the field starts.
    line = _line(event)
    if line is not None and path not in lines:
        lines[path] = line


__all__ = ["DEFAULT_LIMITS", "WITH_LIBYAML", "YamlDocument", "YamlLimits", "read_yaml"]
