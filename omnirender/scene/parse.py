"""Scene-file text to plain data, with the limits that keep hostile files harmless.

JSON goes through :mod:`json`, YAML through PyYAML's safe constructor (with
libyaml's parser when it is installed) and a composer written here, without
recursion, that enforces the limits of :class:`ParseLimits` while it reads:

* **nesting** deeper than ``max_depth`` levels is refused (deep *graphs* are
  written with ``definitions``, see :mod:`omnirender.scene.files`, so a scene
  file never needs deep nesting);
* **YAML aliases** that would expand the document by more than
  ``max_alias_nodes`` nodes (a "billion laughs" file of ten lines), and aliases
  that refer to the collection they are in (a document that contains itself);
* **duplicate keys** in a mapping/object (the later value would silently win).

Every refusal is a :class:`~omnirender.scene.files.SceneFileError` carrying
the JSON path of the offending element (``root.contents[3].radius``).  Only
JSON's types come out: YAML timestamps, sets and binary values are refused too.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from typing import Any

__all__ = ["ParseLimits", "LIMITS", "parse_json", "parse_yaml", "ParseError"]


@dataclass(frozen=True)
class ParseLimits:
    """Limits of what a scene file may ask of the reader (see the module docs)."""

    #: Deepest nesting of objects/mappings and lists (the writer stays far below it).
    max_depth: int = 256
    #: Most nodes YAML aliases may add to a document once expanded.
    max_alias_nodes: int = 1_000_000


LIMITS = ParseLimits()


class ParseError(ValueError):
    """A refusal while parsing; ``path`` is the JSON path (the caller turns it into a SceneFileError)."""

    def __init__(self, path: str, message: str) -> None:
        super().__init__(f"{path}: {message}" if path else message)
        self.path = path
        self.reason = message


def join_path(segments: list[str]) -> str:
    """``["root", ".contents", "[2]"]`` -> ``root.contents[2]``."""
    return "".join(segments).lstrip(".")


# -- JSON ------------------------------------------------------------------------------
class DuplicateKeys(dict):
    """An object that had duplicate keys (reported by the reader, which knows its JSON path)."""

    duplicates: list[str]


def _object_pairs(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out = dict(pairs)
    if len(out) == len(pairs):
        return out
    seen: set[str] = set()
    dups = []
    for key, _ in pairs:
        if key in seen and key not in dups:
            dups.append(key)
        seen.add(key)
    flagged = DuplicateKeys(out)
    flagged.duplicates = dups
    return flagged


def _reject_constant(name: str) -> Any:
    raise ValueError(f"{name} is not allowed (numbers must be finite)")


def parse_json(text: str, limits: ParseLimits = LIMITS) -> Any:
    """Parse JSON text.  NaN/Infinity are refused; objects with duplicate keys come back as
    :class:`DuplicateKeys` (the reader reports them with their path); nesting beyond what
    the parser can take is refused here with the path where it passes ``limits.max_depth``.
    """
    try:
        return json.loads(text, parse_constant=_reject_constant, object_pairs_hook=_object_pairs)
    except RecursionError:
        path = _json_depth_path(text, limits.max_depth)
        raise ParseError(path, nesting_message(limits.max_depth)) from None


def nesting_message(limit: int) -> str:
    return (
        f"nested deeper than {limit} levels; scene files keep nesting shallow (deep node graphs are written "
        "as 'definitions' referred to with $ref, as om.save does)"
    )


_JSON_TOKENS = re.compile(r'"(?:[^"\\]|\\.)*"|[\[\]{},:]')


def _json_depth_path(text: str, limit: int) -> str:
    """The JSON path at which ``text`` first nests deeper than ``limit`` levels ("" if it never does)."""
    stack: list[list[Any]] = []  # [kind, key or index, expecting a key]
    segments: list[str] = []
    for m in _JSON_TOKENS.finditer(text):
        tok = m.group()
        if tok in "{[":
            if stack:
                top = stack[-1]
                segments.append(f".{top[1]}" if top[0] == "{" else f"[{top[1]}]")
            if len(stack) >= limit:
                return join_path(segments)
            stack.append(["{", "", True] if tok == "{" else ["[", 0, False])
        elif tok in "}]":
            if stack:
                stack.pop()
            if segments and len(segments) > len(stack) - 1 and stack:
                segments.pop()
        elif tok == ",":
            if stack:
                top = stack[-1]
                if top[0] == "[":
                    top[1] += 1
                else:
                    top[2] = True
        elif tok == ":":
            if stack:
                stack[-1][2] = False
        elif stack and stack[-1][0] == "{" and stack[-1][2]:
            try:
                stack[-1][1] = json.loads(tok)
            except ValueError:
                stack[-1][1] = tok
    return ""


# -- YAML ------------------------------------------------------------------------------


def parse_yaml(text: str, limits: ParseLimits = LIMITS) -> Any:
    """Parse YAML text safely (see the module docs); raises ParseError or ``yaml.YAMLError``.

    libyaml's fast parser is used when PyYAML has it.  libyaml has limits of its own (newer
    versions refuse flow collections nested 1000 deep, with their own wording, while scanning ahead
    of the composer), so when it refuses a document the text is read again by PyYAML's pure-Python
    parser, which has none: the composer's limits then decide, and a document nested too deep is
    refused with omnirender's message and path whatever the installed PyYAML does.
    """
    import yaml

    fast = _loader_class(pure=False)
    try:
        return _load(fast, text, limits)
    except yaml.YAMLError as fast_error:
        pure = _loader_class(pure=True)
        if pure is fast:
            raise
        try:
            return _load(pure, text, limits)
        except yaml.YAMLError:
            raise fast_error from None


def _load(loader_class: type, text: str, limits: ParseLimits) -> Any:
    loader = loader_class(text)
    loader.limits = limits
    try:
        return loader.get_single_data()
    finally:
        loader.dispose()


_LOADERS: dict[bool, type] = {}


def _loader_class(pure: bool = False) -> type:
    """The scene-file loader class: libyaml's parser unless ``pure`` (or libyaml is missing)."""
    if pure in _LOADERS:
        return _LOADERS[pure]
    from yaml.constructor import SafeConstructor
    from yaml.resolver import Resolver

    parser_bases: tuple[type, ...]
    try:
        if pure:
            raise ImportError
        from yaml._yaml import CParser  # libyaml: much faster on big files

        parser_bases = (CParser,)
    except ImportError:
        if not pure:  # pragma: no cover - depends on the PyYAML build
            _LOADERS[False] = _loader_class(pure=True)
            return _LOADERS[False]
        from yaml.parser import Parser
        from yaml.reader import Reader
        from yaml.scanner import Scanner

        parser_bases = (Reader, Scanner, Parser)

    class _Constructor(SafeConstructor):
        """The safe constructor minus the types JSON does not have."""

    for tag in ("timestamp", "set", "binary", "omap", "pairs"):
        _Constructor.add_constructor(f"tag:yaml.org,2002:{tag}", _refuse_tag)

    class Loader(_LimitedComposer, *parser_bases, _Constructor, Resolver):  # type: ignore[misc]
        def __init__(self, stream: str) -> None:
            parser_bases[0].__init__(self, stream)  # CParser or Reader take the text
            for base in parser_bases[1:]:  # Scanner and Parser take nothing
                base.__init__(self)
            _Constructor.__init__(self)
            Resolver.__init__(self)
            self.limits = LIMITS

    Loader.__name__ = "SceneYAMLLoader"
    _LOADERS[pure] = Loader
    return Loader


def _refuse_tag(constructor: Any, node: Any) -> Any:
    from yaml.constructor import ConstructorError

    kind = node.tag.rsplit(":", 1)[-1]
    raise ConstructorError(
        None, None, f"YAML {kind} values are not allowed in scene files (only JSON's types)", node.start_mark
    )


class _Frame:
    __slots__ = ("node", "anchor", "index", "key", "keys", "size")

    def __init__(self, node: Any, anchor: str | None) -> None:
        self.node = node
        self.anchor = anchor
        self.index = 0
        self.key: Any = None
        self.keys: dict[tuple[str, str], Any] = {}
        self.size = 1


class _LimitedComposer:
    """PyYAML's composer without recursion, enforcing :class:`ParseLimits` (see the module docs)."""

    limits: ParseLimits

    def get_single_node(self) -> Any:
        from yaml.composer import ComposerError
        from yaml.events import StreamEndEvent

        self.get_event()  # StreamStart
        document = None
        if not self.check_event(StreamEndEvent):
            document = self.compose_document()
        if not self.check_event(StreamEndEvent):
            event = self.get_event()
            raise ComposerError(
                "expected a single document in the stream", None, "but found another document", event.start_mark
            )
        self.get_event()
        return document

    def compose_document(self) -> Any:
        self.get_event()  # DocumentStart
        node = self._compose()
        self.get_event()  # DocumentEnd
        return node

    def _compose(self) -> Any:
        from yaml.events import (
            AliasEvent,
            MappingEndEvent,
            MappingStartEvent,
            ScalarEvent,
            SequenceEndEvent,
            SequenceStartEvent,
        )
        from yaml.nodes import MappingNode, ScalarNode, SequenceNode

        limits = self.limits
        anchors: dict[str, Any] = {}
        sizes: dict[int, int] = {}
        open_anchors: set[str] = set()
        stack: list[_Frame] = []
        expanded = 0
        root: Any = None

        def path() -> str:
            segments = []
            for frame in stack:
                if isinstance(frame.node, SequenceNode):
                    segments.append(f"[{frame.index}]")
                elif frame.key is not None:
                    segments.append(f".{frame.key.value if isinstance(frame.key, ScalarNode) else '?'}")
            return join_path(segments)

        def attach(node: Any, size: int) -> Any:
            if not stack:
                return node
            frame = stack[-1]
            frame.size += size
            if isinstance(frame.node, SequenceNode):
                frame.node.value.append(node)
                frame.index += 1
            elif frame.key is None:
                if not isinstance(node, ScalarNode):
                    raise ParseError(path(), "mapping keys must be plain strings")
                frame.key = node
            else:
                key = frame.key
                ident = (key.tag, key.value)
                if ident in frame.keys and key.value != "<<":
                    line = key.start_mark.line + 1
                    raise ParseError(
                        path(),
                        f"duplicate key {key.value!r} (line {line}; the first is on line "
                        f"{frame.keys[ident].start_mark.line + 1}); a mapping names each key once",
                    )
                frame.keys[ident] = key
                frame.node.value.append((key, node))
                frame.key = None
            return None

        def open_collection(node: Any, anchor: str | None) -> None:
            if len(stack) >= limits.max_depth:
                raise ParseError(path(), nesting_message(limits.max_depth))
            if anchor is not None:
                anchors[anchor] = node
                open_anchors.add(anchor)
            stack.append(_Frame(node, anchor))

        while True:
            event = self.get_event()
            cls = event.__class__
            if cls is ScalarEvent:
                tag = event.tag
                if tag is None or tag == "!":
                    tag = self.resolve(ScalarNode, event.value, event.implicit)
                node = ScalarNode(tag, event.value, event.start_mark, event.end_mark, style=event.style)
                if event.anchor is not None:
                    anchors[event.anchor] = node
                    sizes[id(node)] = 1
                done = attach(node, 1)
            elif cls is AliasEvent:
                anchor = event.anchor
                if anchor in open_anchors:
                    raise ParseError(
                        path(),
                        f"the alias *{anchor} refers to a collection that contains it (a document cannot "
                        "contain itself)",
                    )
                if anchor not in anchors:
                    raise ParseError(path(), f"the alias *{anchor} names no anchor defined before it")
                node = anchors[anchor]
                size = sizes[id(node)]
                expanded += size
                if expanded > limits.max_alias_nodes:
                    raise ParseError(
                        path(),
                        f"YAML aliases expand this document by more than {limits.max_alias_nodes:,} nodes; "
                        "share objects with $id/$ref instead (they are not copied)",
                    )
                done = attach(node, size)
            elif cls is SequenceStartEvent or cls is MappingStartEvent:
                kind = SequenceNode if cls is SequenceStartEvent else MappingNode
                tag = event.tag
                if tag is None or tag == "!":
                    tag = self.resolve(kind, None, event.implicit)
                node = kind(tag, [], event.start_mark, None, flow_style=event.flow_style)
                open_collection(node, event.anchor)
                continue
            elif cls is SequenceEndEvent or cls is MappingEndEvent:
                frame = stack.pop()
                frame.node.end_mark = event.end_mark
                if frame.anchor is not None:
                    open_anchors.discard(frame.anchor)
                    sizes[id(frame.node)] = frame.size
                if frame.key is not None:  # pragma: no cover - the parser never ends a mapping after a key
                    raise ParseError(path(), "a mapping key has no value")
                done = attach(frame.node, frame.size)
            else:  # pragma: no cover - the parser emits only the events above inside a document
                raise ParseError(path(), f"unexpected YAML event {cls.__name__}")
            if done is not None:
                root = done
                return root
