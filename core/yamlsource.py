"""Safe YAML reading that remembers where every value was written.

The materials library and the scenes report each problem as ``FILE:LINE:COL: path: message``
(1-based line and column), every problem of a file at once, never a traceback. This module
reads YAML into plain Python data (``dict`` / ``list`` / ``str`` / ``int`` / ``float`` /
``bool`` / ``None``) and keeps, for every path into that data, the position of the key or item
that produced it, so validation can point back at the source.

How YAML is read here, and why:

- Safe only. Events come from PyYAML's pure-Python parser (``yaml.SafeLoader``); the node tree
  is built here without recursion and converted with ``SafeLoader``'s own scalar rules. Tags
  that would build objects (``!!python/...``, any local ``!tag``, and ``!!binary``, ``!!set``,
  ``!!omap``, ``!!pairs``, which are not plain data) are errors.
- Dates stay text: ``2021-03-04`` is the string ``"2021-03-04"`` so the data stays JSON-like;
  models parse it if they want a date.
- YAML 1.1 scalar rules are kept for values, surprises included: ``yes/no/on/off`` are booleans,
  ``012`` is octal (10), ``1:30`` is sexagesimal (90), ``1e3`` (no dot) is a string. The models
  reject a boolean where they expect text, so ``country: NO`` still ends as a located error.
- Mapping keys must be strings. A plain key YAML reads as something else (``1:``, ``on:``,
  ``~:``) is an error asking to quote it, rather than a silently converted key.
- Duplicate keys are errors, at the second occurrence, naming the line of the first.
- Merge keys (``<<: *base`` or ``<<: [*a, *b]``) are supported as in the YAML merge-key spec:
  keys written in the mapping win over merged ones; among several sources the first wins. A
  merged key is located where it was written (inside the anchored mapping).
- Non-finite floats (``.nan``, ``.inf``, ``-.inf``, or ``1e999`` overflowing) are errors: a NaN in
  a fabric parameter poisons every result downstream without an error of its own.
- Hostile input fails fast: a byte limit on the file, a depth limit on nesting, and a limit on
  the node count *after* alias expansion, checked as each alias is read (so a "billion laughs"
  file fails in microseconds, not after expanding). Aliases to an enclosing node are errors.
- Empty documents (a stray ``---``) are skipped; a file with no document at all is an error.

Errors about the whole file (cannot read, empty, too large) are placed at line 1, column 1.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast

import yaml
from yaml.events import (
    AliasEvent,
    CollectionEndEvent,
    CollectionStartEvent,
    DocumentEndEvent,
    DocumentStartEvent,
    MappingStartEvent,
    ScalarEvent,
)
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode

__all__ = [
    "MAX_BYTES",
    "MAX_DEPTH",
    "MAX_NODES",
    "Document",
    "SourceError",
    "YamlPath",
    "YamlSourceError",
    "format_path",
    "load_yaml",
    "load_yaml_text",
]

YamlPath = tuple[str | int, ...]
"""A path into loaded data: mapping keys (``str``) and list indices (``int``)."""

MAX_BYTES = 20 * 1024 * 1024
"""Largest file read, in bytes. A materials library file is kilobytes."""

MAX_DEPTH = 64
"""Deepest nesting of mappings and lists, counted through aliases."""

MAX_NODES = 1_000_000
"""Most values (scalars, mappings, lists) in one file, counting every alias expansion."""

# Beyond this many invalid bytes or characters the rest are the same mistake; stop listing.
_MAX_LISTED = 10

# The converter recurses once per nesting level (a few frames each), so the depth limit must
# stay well inside Python's recursion limit.
_DEPTH_CEILING = 200

_YAML = "tag:yaml.org,2002:"
_STR, _INT, _FLOAT, _BOOL, _NULL = (_YAML + t for t in ("str", "int", "float", "bool", "null"))
_MAP, _SEQ, _MERGE = _YAML + "map", _YAML + "seq", _YAML + "merge"
# Read as their written text: dates stay strings; "=" and "<<" outside a key are just text.
_AS_TEXT = {_YAML + "timestamp", _YAML + "value", _MERGE}

# What a non-string key was read as, for the message asking to quote it.
_KEY_KINDS = {
    _INT: "an integer",
    _FLOAT: "a number",
    _BOOL: "a boolean (YAML 1.1 reads yes/no/on/off as booleans)",
    _NULL: "null",
    _YAML + "timestamp": "a date",
}

# Line breaks as PyYAML counts them, so positions computed here agree with its marks.
_LINE_BREAK = re.compile("\r\n|[\n\r\x85\u2028\u2029]")


@dataclass(frozen=True)
class SourceError:
    """One problem, located: 1-based ``line`` and ``column`` in ``file``.

    ``path`` is the dotted path of the field (``fabrics[0].tow_width_mm``), or ``""`` when the
    problem is not about one field (syntax errors, whole-file errors).
    """

    file: str
    line: int
    column: int
    path: str
    message: str

    def __str__(self) -> str:
        where = f"{self.file}:{self.line}:{self.column}"
        return f"{where}: {self.path}: {self.message}" if self.path else f"{where}: {self.message}"


class YamlSourceError(Exception):
    """Every problem found in one file; ``str()`` lists them one per line, in file order."""

    def __init__(self, errors: Sequence[SourceError]) -> None:
        # The errors are the only argument so the exception pickles across process pools.
        super().__init__(list(errors))
        self.errors: list[SourceError] = list(errors)

    def __str__(self) -> str:
        return "\n".join(str(error) for error in self.errors)


def format_path(path: YamlPath) -> str:
    """``("fabrics", 0, "tow_width_mm")`` -> ``"fabrics[0].tow_width_mm"``."""
    text = ""
    for step in path:
        if isinstance(step, int):
            text += f"[{step}]"
        else:
            text += f".{step}" if text else step
    return text


Position = tuple[int, int]


# The three records below are private to reading a file and never compared or shown: plain
# slotted classes, not dataclasses, because creating a dataclass execs its generated methods,
# which costs start-up (`materials list` reads the library) and buys nothing here.


class _Entry:
    """One key of a mapping or item of a list, as written."""

    __slots__ = ("key", "value", "where")

    def __init__(self, key: Position, value: Position, where: _Where) -> None:
        self.key = key  # the key (for a list item: the item itself)
        self.value = value  # the value as written here (an alias's own, not its anchor's)
        self.where = where  # the value's own positions (for an alias: the anchored node's)


class _Where:
    """Positions of one node and its children; a tree parallel to the loaded data."""

    __slots__ = ("entries", "position")

    def __init__(self, position: Position, entries: dict[str | int, _Entry]) -> None:
        self.position = position
        self.entries = entries


_NO_ENTRIES: dict[str | int, _Entry] = {}


@dataclass(frozen=True)
class Document:
    """One YAML document of a file: its plain data and where each part of it was written."""

    file: str
    data: Any
    _where: _Where = field(repr=False, compare=False)

    def locate(self, path: YamlPath) -> Position:
        """(line, column) of the key at ``path`` (of the item, for a list index).

        For a path that does not exist (a missing field, an index past the end), the position
        of its closest existing ancestor: the field that should have held it. ``()`` is the
        document's root value.
        """
        entry = self._closest(path)
        return entry.key if entry is not None else self._where.position

    def locate_value(self, path: YamlPath) -> Position:
        """(line, column) of the value at ``path``, for "this value is wrong" messages.

        Same fallback to the closest existing ancestor as :meth:`locate`.
        """
        entry = self._closest(path)
        return entry.value if entry is not None else self._where.position

    def error(self, path: YamlPath, message: str, *, at_value: bool = False) -> SourceError:
        """A :class:`SourceError` about ``path``, at its key (or at its value)."""
        line, column = self.locate_value(path) if at_value else self.locate(path)
        return SourceError(self.file, line, column, format_path(path), message)

    def _closest(self, path: YamlPath) -> _Entry | None:
        where, found = self._where, None
        for step in path:
            entry = where.entries.get(step)
            # bool is an int subclass: True must not find list item 1.
            if entry is None or isinstance(step, bool):
                break
            found, where = entry, entry.where
        return found


def load_yaml(
    path: str | Path,
    *,
    max_bytes: int = MAX_BYTES,
    max_depth: int = MAX_DEPTH,
    max_nodes: int = MAX_NODES,
) -> list[Document]:
    """Read every document of a UTF-8 YAML file.

    Raises :class:`YamlSourceError` with every problem found; nothing else for bad input.
    """
    file = str(path)
    try:
        with open(path, "rb") as stream:
            # Read one byte past the limit: enough to tell, without reading a huge file whole.
            raw = stream.read(max_bytes + 1)
    except OSError as error:
        reason = error.strerror or str(error)
        raise YamlSourceError([_whole_file(file, f"cannot read file: {reason}")]) from None
    if len(raw) > max_bytes:
        raise YamlSourceError([_whole_file(file, _too_large(max_bytes))])
    text = _decode_utf8(raw, file)
    return load_yaml_text(text, file, max_bytes=max_bytes, max_depth=max_depth, max_nodes=max_nodes)


def load_yaml_text(
    text: str,
    file: str = "<string>",
    *,
    max_bytes: int = MAX_BYTES,
    max_depth: int = MAX_DEPTH,
    max_nodes: int = MAX_NODES,
) -> list[Document]:
    """Read every document of YAML ``text``; ``file`` is the name used in errors.

    Raises :class:`YamlSourceError` with every problem found; nothing else for bad input.
    """
    if not 0 < max_depth <= _DEPTH_CEILING:
        raise ValueError(f"max_depth must be within 1..{_DEPTH_CEILING}, got {max_depth}")
    # Characters never outnumber UTF-8 bytes, so the cheap length check settles most texts.
    if len(text) > max_bytes or len(text.encode("utf-8", "surrogatepass")) > max_bytes:
        raise YamlSourceError([_whole_file(file, _too_large(max_bytes))])
    text = text.removeprefix("\ufeff")

    errors = _unprintable_characters(text, file)
    if errors:
        raise YamlSourceError(errors)

    documents: list[Document] = []
    composer = _Composer(text, file, max_depth, max_nodes, errors)
    converter = _Converter(file, errors)
    for root in composer.documents():
        data, where = converter.document(root)
        documents.append(Document(file, data, where))
    if not documents and not errors:
        errors.append(_whole_file(file, "file is empty: it holds no YAML document"))
    if errors:
        raise YamlSourceError(sorted(errors, key=lambda e: (e.line, e.column)))
    return documents


def _whole_file(file: str, message: str) -> SourceError:
    return SourceError(file, 1, 1, "", message)


def _too_large(max_bytes: int) -> str:
    return f"file is larger than the limit of {max_bytes} bytes"


def _line_column(text: str, index: int) -> Position:
    """1-based (line, column) of character ``index``, counting line breaks as PyYAML does."""
    line, line_start = 1, 0
    for match in _LINE_BREAK.finditer(text, 0, index):
        line, line_start = line + 1, match.end()
    return line, index - line_start + 1


def _decode_utf8(raw: bytes, file: str) -> str:
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        pass
    errors: list[SourceError] = []
    start = 0
    while len(errors) < _MAX_LISTED:
        try:
            raw[start:].decode("utf-8")
            break
        except UnicodeDecodeError as error:
            offset = start + error.start
            start += error.end
        # Every byte before the first bad one is valid, so its position is exact; for later
        # ones, each earlier bad sequence counts as one character (as editors show it).
        prefix = raw[:offset].decode("utf-8", "replace")
        line, column = _line_column(prefix, len(prefix))
        errors.append(
            SourceError(
                file,
                line,
                column,
                "",
                f"not UTF-8: byte 0x{raw[offset]:02x} at byte offset {offset}; "
                "save the file as UTF-8",
            )
        )
    raise YamlSourceError(errors)


def _unprintable_characters(text: str, file: str) -> list[SourceError]:
    # PyYAML rejects these too, but only the first and by character index.
    errors: list[SourceError] = []
    for match in yaml.reader.Reader.NON_PRINTABLE.finditer(text):
        if len(errors) == _MAX_LISTED:
            break
        line, column = _line_column(text, match.start())
        code = ord(match.group())
        errors.append(
            SourceError(file, line, column, "", f"character U+{code:04X} is not allowed in YAML")
        )
    return errors


def _position(mark: yaml.Mark) -> Position:
    return mark.line + 1, mark.column + 1


def _syntax_error(file: str, error: yaml.MarkedYAMLError) -> SourceError:
    message = f"syntax error: {error.problem or error.context or 'invalid YAML'}"
    if error.problem and error.context:
        message += f" ({error.context}"
        if error.context_mark is not None:
            line, column = _position(error.context_mark)
            message += f" at line {line}, column {column}"
        message += ")"
    if error.problem and "'\\t'" in error.problem:
        message += "; YAML does not allow tabs for indentation, use spaces"
    mark = error.problem_mark or error.context_mark
    line, column = _position(mark) if mark is not None else (1, 1)
    return SourceError(file, line, column, "", message)


class _AliasNode(Node):
    """An alias as written (``*name``), pointing at the anchored node.

    PyYAML's composer puts the anchored node itself in place of an alias, losing where the
    alias was written; errors and ``locate_value`` need that place.
    """

    id = "alias"

    def __init__(self, name: str, target: Node, start_mark: yaml.Mark, end_mark: yaml.Mark):
        super().__init__(target.tag, target, start_mark, end_mark)
        self.name = name
        self.target = target


def _marks(event: yaml.Event) -> tuple[yaml.Mark, yaml.Mark]:
    """An event's start and end marks (the stubs allow None; the pure-Python parser always sets
    them)."""
    return cast(yaml.Mark, event.start_mark), cast(yaml.Mark, event.end_mark)


def _resolved(node: Node) -> Node:
    return node.target if isinstance(node, _AliasNode) else node


class _LimitExceeded(Exception):
    """A hostile-input limit was hit; the error is recorded, reading stops."""


class _Open:
    """A mapping or list still being read."""

    __slots__ = ("key", "node")

    def __init__(self, node: MappingNode | SequenceNode) -> None:
        self.node = node
        self.key: Node | None = None  # a mapping key waiting for its value


class _ParsedEvents(yaml.SafeLoader):
    """Events already parsed, served as ``SafeLoader`` serves its own (and its resolver)."""

    def __init__(self, events: list[Any]) -> None:
        super().__init__("")
        self._events = events
        self._next = 0

    def check_event(self, *choices: Any) -> bool:
        return self._next < len(self._events)

    def get_event(self) -> Any:
        event = self._events[self._next]
        self._next += 1
        return event


def _event_source(text: str) -> Any:
    """The parser events of ``text``: libyaml's (some 40 times faster, so reading the bundled
    library is not most of ``preform materials list``) when it parses the whole text, else
    PyYAML's own parser, whose syntax errors and partial trees the messages here are built on.

    The events of the two agree, marks included, on every file libyaml parses (checked on
    the project's files in tests/test_yamlsource.py); libyaml is only the faster way to them.
    """
    fast = getattr(yaml, "CSafeLoader", None)
    if fast is not None:
        parser = fast(text)
        try:
            events = []
            while parser.check_event():
                events.append(parser.get_event())
            return _ParsedEvents(events)
        except yaml.YAMLError:
            pass  # read it again with PyYAML's parser, for its located message
        finally:
            parser.dispose()
    return yaml.SafeLoader(text)


class _Composer:
    """Builds the node tree of each document from parser events, without recursion.

    Depth and expanded node count are checked as each node or alias is read, so hostile input
    stops before it costs anything.
    """

    def __init__(
        self, text: str, file: str, max_depth: int, max_nodes: int, errors: list[SourceError]
    ) -> None:
        self._loader = _event_source(text)  # a parser and resolver only; nothing constructed
        self._file = file
        self._max_depth = max_depth
        self._max_nodes = max_nodes
        self._errors = errors
        self._nodes = 0  # values read so far in the file, every alias counted as its expansion
        # Keyed by the node itself, not id(): ids of freed nodes are reused.
        self._size: dict[Node, int] = {}  # values in a node, aliases expanded
        self._height: dict[Node, int] = {}  # nesting levels in a node, aliases followed
        self._anchors: dict[str, Node] = {}
        self._open: list[_Open] = []
        self._root: Node | None = None

    def documents(self) -> Iterator[Node]:
        """Each non-empty document's root node; stops at a syntax error or a limit."""
        try:
            while self._loader.check_event():
                event = self._loader.get_event()
                if isinstance(event, DocumentStartEvent):
                    # Anchors do not reach across documents.
                    self._anchors, self._root = {}, None
                    self._size, self._height = {}, {}
                elif isinstance(event, DocumentEndEvent):
                    if self._root is not None and not _is_empty(self._root):
                        yield self._root
                elif isinstance(event, ScalarEvent | CollectionStartEvent | AliasEvent):
                    self._start(event)
                elif isinstance(event, CollectionEndEvent):
                    self._end()
        except yaml.MarkedYAMLError as error:
            self._errors.append(_syntax_error(self._file, error))
            # What was read before the syntax error may hold more errors worth reporting now.
            partial = self._open[0].node if self._open else self._root
            if partial is not None:
                yield partial
        except _LimitExceeded:
            pass
        finally:
            self._loader.dispose()

    def _start(self, event: ScalarEvent | CollectionStartEvent | AliasEvent) -> None:
        if isinstance(event, AliasEvent):
            self._add(self._alias(event))
            return
        start, end = _marks(event)
        node: Node
        tag = event.tag
        if isinstance(event, ScalarEvent):
            if tag is None or tag == "!":
                tag = self._loader.resolve(ScalarNode, event.value, event.implicit)
            node = ScalarNode(tag, event.value, start, end, event.style)
        else:
            if len(self._open) >= self._max_depth:
                self._stop(start, f"nesting deeper than {self._max_depth} levels")
            kind = MappingNode if isinstance(event, MappingStartEvent) else SequenceNode
            if tag is None or tag == "!":
                tag = self._loader.resolve(kind, None, event.implicit)
            node = kind(tag, [], start, None, event.flow_style)
        self._count(1, start, "")
        if event.anchor is not None:
            self._anchor(event.anchor, node)
        if isinstance(node, MappingNode | SequenceNode):
            # Open before its children are read, so an alias inside it is seen as recursive.
            self._open.append(_Open(node))
        else:
            self._size[node], self._height[node] = 1, 0
            self._add(node)

    def _end(self) -> None:
        node = self._open.pop().node
        children: list[Node] = (
            [c for pair in node.value for c in pair]
            if isinstance(node, MappingNode)
            else node.value
        )
        self._size[node] = 1 + sum(self._size[child] for child in children)
        self._height[node] = 1 + max((self._height[c] for c in children), default=0)
        self._add(node)

    def _alias(self, event: AliasEvent) -> Node:
        start, end = _marks(event)
        name = str(event.anchor)
        target = self._anchors.get(name)
        if target is None or any(frame.node is target for frame in self._open):
            self._error(
                start,
                f"alias *{name} has no anchor &{name} before it in this document"
                if target is None
                else f"alias *{name} is inside the node it refers to (a recursive structure)",
            )
            placeholder = ScalarNode(_NULL, "", start, end)
            self._size[placeholder], self._height[placeholder] = 1, 0
            return placeholder
        height = self._height[target]
        if len(self._open) + height > self._max_depth:
            self._stop(start, f"alias *{name} nests deeper than {self._max_depth} levels here")
        size = self._size[target]
        self._count(size, start, f"alias *{name} expands to {size} values and")
        alias = _AliasNode(name, target, start, end)
        self._size[alias], self._height[alias] = size, height
        return alias

    def _anchor(self, name: str, node: Node) -> None:
        first = self._anchors.get(name)
        if first is not None:
            line, _ = _position(first.start_mark)
            self._error(node.start_mark, f"anchor &{name} is defined twice (first at line {line})")
        self._anchors[name] = node

    def _add(self, node: Node) -> None:
        if not self._open:
            self._root = node
            return
        frame = self._open[-1]
        if isinstance(frame.node, SequenceNode):
            frame.node.value.append(node)
        elif frame.key is None:
            frame.key = node
        else:
            frame.node.value.append((frame.key, node))
            frame.key = None

    def _count(self, values: int, mark: yaml.Mark, what: str) -> None:
        self._nodes += values
        if self._nodes > self._max_nodes:
            subject = f"{what} the file" if what else "the file"
            self._stop(mark, f"{subject} exceeds the limit of {self._max_nodes} values")

    def _stop(self, mark: yaml.Mark, message: str) -> None:
        # No field path: for hostile nesting it would be as long as the nesting.
        self._error(mark, message, with_path=False)
        raise _LimitExceeded

    def _error(self, mark: yaml.Mark, message: str, *, with_path: bool = True) -> None:
        line, column = _position(mark)
        path = self._path() if with_path else ""
        self._errors.append(SourceError(self._file, line, column, path, message))

    def _path(self) -> str:
        """Dotted path of the node being read, for errors found while composing."""
        path: list[str | int] = []
        for frame in self._open:
            if isinstance(frame.node, SequenceNode):
                path.append(len(frame.node.value))
            elif frame.key is not None and isinstance(_resolved(frame.key), ScalarNode):
                path.append(str(_resolved(frame.key).value))
        return format_path(tuple(path))


def _is_empty(node: Node) -> bool:
    """An implicit empty document, e.g. after a stray ``---``: not an explicit ``null``."""
    return (
        isinstance(node, ScalarNode) and node.tag == _NULL and node.value == "" and not node.style
    )


class _Converter:
    """Turns node trees into plain data plus positions, collecting every error on the way.

    Recursion is safe: the composer has already bounded the depth, aliases included.
    """

    def __init__(self, file: str, errors: list[SourceError]) -> None:
        self._file = file
        self._errors = errors
        self._scalars = yaml.SafeLoader("")  # only for SafeLoader's scalar rules
        # Each node is converted once, so an anchored node's errors are reported once (at the
        # anchor); aliases get copies of its data.
        self._done: dict[Node, tuple[Any, _Where]] = {}

    def document(self, root: Node) -> tuple[Any, _Where]:
        self._done = {}  # anchors do not reach across documents
        return self.convert(root, ())

    def convert(self, node: Node, path: YamlPath) -> tuple[Any, _Where]:
        if isinstance(node, _AliasNode):
            data, where = self.convert(node.target, path)
            return _copy(data), where
        done = self._done.get(node)
        if done is None:
            if isinstance(node, MappingNode):
                done = self._mapping(node, path)
            elif isinstance(node, SequenceNode):
                done = self._sequence(node, path)
            else:
                assert isinstance(node, ScalarNode)
                done = self._scalar(node, path), _Where(_position(node.start_mark), _NO_ENTRIES)
            self._done[node] = done
        return done

    def _sequence(self, node: SequenceNode, path: YamlPath) -> tuple[Any, _Where]:
        if node.tag != _SEQ:
            self._tag_error(node, path)
        data: list[Any] = []
        entries: dict[str | int, _Entry] = {}
        for index, item in enumerate(node.value):
            value, where = self.convert(item, (*path, index))
            data.append(value)
            at = _position(item.start_mark)
            entries[index] = _Entry(at, at, where)
        return data, _Where(_position(node.start_mark), entries)

    def _mapping(self, node: MappingNode, path: YamlPath) -> tuple[Any, _Where]:
        if node.tag != _MAP:
            self._tag_error(node, path)
        data: dict[str, Any] = {}
        entries: dict[str | int, _Entry] = {}
        merge: tuple[Node, Node] | None = None
        for key_node, value_node in node.value:
            key_target = _resolved(key_node)
            if isinstance(key_target, ScalarNode) and key_target.tag == _MERGE:
                if merge is not None:
                    self._duplicate(key_node, (*path, "<<"), _position(merge[0].start_mark))
                else:
                    merge = key_node, value_node
                continue
            key = self._key(key_node, path)
            # A rejected key still has its value read, for the errors inside it.
            shown = key_target.value if isinstance(key_target, ScalarNode) else "?"
            value_path = (*path, key if key is not None else str(shown))
            value, where = self.convert(value_node, value_path)
            if key is None:
                continue
            if key in entries:
                self._duplicate(key_node, value_path, entries[key].key)
                continue
            data[key] = value
            entries[key] = _Entry(
                _position(key_node.start_mark), _position(value_node.start_mark), where
            )
        if merge is not None:
            self._merge(merge[1], path, data, entries)
        return data, _Where(_position(node.start_mark), entries)

    def _merge(
        self, value: Node, path: YamlPath, data: dict[str, Any], entries: dict[str | int, _Entry]
    ) -> None:
        """Add the keys of ``<<: source`` (or ``<<: [first, second]``) that are not yet there."""
        target = _resolved(value)
        sources = target.value if isinstance(target, SequenceNode) else [value]
        for source in sources:
            if not isinstance(_resolved(source), MappingNode):
                self._error(source, path, "merge key '<<' takes a mapping or a list of mappings")
                continue
            merged, where = self.convert(source, path)
            if not isinstance(merged, dict):
                continue  # wrongly tagged; already reported
            for key, item in merged.items():
                if key not in data:
                    data[key] = item
                    entries[key] = where.entries[key]

    def _key(self, node: Node, path: YamlPath) -> str | None:
        target = _resolved(node)
        if not isinstance(target, ScalarNode):
            shape = "a mapping" if isinstance(target, MappingNode) else "a list"
            self._error(node, path, f"mapping keys must be strings, not {shape}")
            return None
        if target.tag == _STR:
            return str(target.value)
        kind = _KEY_KINDS.get(target.tag)
        if kind is None:
            self._tag_error(target, path)
        elif target.value == "":
            self._error(node, path, "mapping key is empty")
        else:
            self._error(
                node,
                (*path, target.value),
                f"key '{target.value}' is read as {kind}; keys must be strings, "
                f"so quote it: '{target.value}':",
            )
        return None

    def _scalar(self, node: ScalarNode, path: YamlPath) -> Any:
        tag, text = node.tag, node.value
        if tag == _STR or tag in _AS_TEXT:
            return text
        if tag == _NULL:
            return None
        rules = {
            _INT: ("an integer", self._scalars.construct_yaml_int),
            _FLOAT: ("a number", self._scalars.construct_yaml_float),
            _BOOL: ("a boolean", self._scalars.construct_yaml_bool),
        }
        if tag not in rules:
            self._tag_error(node, path)
            return None
        kind, construct = rules[tag]
        try:
            value = construct(node)
        except (ValueError, KeyError, yaml.YAMLError):
            self._error(node, path, f"'{text}' is not {kind}")
            return None
        if isinstance(value, float) and not math.isfinite(value):
            self._error(
                node,
                path,
                f"non-finite number '{text}' is not allowed; write a finite value "
                "(or leave the field out if it is unknown)",
            )
            return None
        return value

    def _tag_error(self, node: Node, path: YamlPath) -> None:
        tag = str(node.tag)
        shown = "!!" + tag.removeprefix(_YAML) if tag.startswith(_YAML) else tag
        if "python/" in tag:
            why = "it would construct a Python object"
        elif tag in (_STR, _INT, _FLOAT, _BOOL, _NULL, _MAP, _SEQ):
            shape = "a mapping" if isinstance(node, MappingNode) else "a list"
            why = f"it does not fit {'a scalar' if isinstance(node, ScalarNode) else shape}"
        elif tag.startswith(_YAML):
            why = "it does not give plain data"
        else:
            why = "it is not a standard YAML tag"
        self._error(
            node,
            path,
            f"tag {shown} is not allowed: {why}; "
            "fabric files hold plain mappings, lists, text, numbers, booleans and null",
        )

    def _duplicate(self, node: Node, path: YamlPath, first: Position) -> None:
        self._error(node, path, f"duplicate key '{path[-1]}' (first at line {first[0]})")

    def _error(self, node: Node, path: YamlPath, message: str) -> None:
        line, column = _position(node.start_mark)
        self._errors.append(SourceError(self._file, line, column, format_path(path), message))


def _copy(data: Any) -> Any:
    """An independent copy of plain data, so editing one alias's value leaves the others."""
    if isinstance(data, dict):
        return {key: _copy(value) for key, value in data.items()}
    if isinstance(data, list):
        return [_copy(value) for value in data]
    return data
