"""Typed, located reading of YAML documents.

:class:`Node` pairs a parsed value with its key path (``arms[1].joint_limits.elbow``) and its
place in the file, so every reader can raise an error that says where and what was expected.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import yaml

from sdar_tamp.errors import SourceLocation
from sdar_tamp.textfile import ErrorFactory, read_text
from sdar_tamp.world.errors import WorldFileError


@dataclass(frozen=True)
class Node:
    """A value of a YAML document with its key path and source position."""

    value: object
    path: str
    file: str
    ynode: yaml.Node | None
    error_type: type[WorldFileError] = WorldFileError

    @property
    def location(self) -> SourceLocation:
        if self.ynode is None:
            return SourceLocation(self.file, 1, 1)
        mark = self.ynode.start_mark
        return SourceLocation(self.file, mark.line + 1, mark.column + 1)

    def error(self, expected: str, *, show_value: bool = True) -> WorldFileError:
        """An error at this node: ``path: expected <expected>, got <value>``."""
        where = f"{self.path}: " if self.path else ""
        got = f", got {self.value!r}" if show_value else ""
        return self.error_type(f"{where}expected {expected}{got}", self.location)

    def _child(self, key: str | int, value: object, ynode: yaml.Node | None) -> Node:
        if isinstance(key, int):
            path = f"{self.path}[{key}]"
        else:
            path = f"{self.path}.{key}" if self.path else key
        return Node(value, path, self.file, ynode, self.error_type)

    def mapping(self, required: Sequence[str], optional: Sequence[str] = ()) -> dict[str, Node]:
        """The children of a mapping with exactly the ``required`` keys plus any ``optional``."""
        if not isinstance(self.value, dict):
            raise self.error(f"a mapping with keys {list(required)}")
        ykeys: dict[str, yaml.Node] = {}
        if isinstance(self.ynode, yaml.MappingNode):
            for knode, vnode in self.ynode.value:
                ykeys[str(knode.value)] = vnode
        allowed = [*required, *optional]
        out: dict[str, Node] = {}
        for key, value in self.value.items():
            if key not in allowed:
                bad = self._child(str(key), value, ykeys.get(str(key), self.ynode))
                raise self.error_type(
                    f"{bad.path}: unknown key {key!r}; expected one of {allowed}", bad.location
                )
            out[key] = self._child(key, value, ykeys.get(key))
        for key in required:
            if key not in out:
                raise self.error(f"key {key!r} (required keys: {list(required)})", show_value=False)
        return out

    def items(self) -> list[Node]:
        """The children of a sequence."""
        if not isinstance(self.value, list):
            raise self.error("a list")
        ynodes: list[yaml.Node | None] = [None] * len(self.value)
        if isinstance(self.ynode, yaml.SequenceNode):
            ynodes = list(self.ynode.value)
        return [self._child(i, v, ynodes[i]) for i, v in enumerate(self.value)]

    def as_str(self) -> str:
        if not isinstance(self.value, str) or not self.value:
            raise self.error("a non-empty string")
        return self.value

    def as_name(self) -> str:
        """An object name: a non-empty string, or an integer written as its digits. A value
        YAML 1.1 reads as a boolean (``on``, ``off``, ``yes``, ``no``, ``true``, ``false``) is
        refused with the advice to quote it."""
        if isinstance(self.value, bool):
            raise self.error_type(
                f"{self.path}: expected a name, got {self.raw_text()!r}, which YAML reads as the "
                f"boolean {self.value}; quote it ('{self.raw_text()}')",
                self.location,
            )
        if isinstance(self.value, int):
            return str(self.value)
        return self.as_str()

    def raw_text(self) -> str:
        """The scalar as written in the file (its parsed value's text without a source)."""
        if isinstance(self.ynode, yaml.ScalarNode):
            return str(self.ynode.value)
        return str(self.value)

    def as_float(self, *, positive: bool = False) -> float:
        value = _number(self.value)
        if value is None or not math.isfinite(value):
            raise self.error("a finite number" + (" > 0" if positive else ""))
        if positive and value <= 0.0:
            raise self.error("a number > 0")
        return value

    def as_floats(self, n: int, what: str, *, positive: bool = False) -> tuple[float, ...]:
        """A list of exactly ``n`` finite numbers."""
        if not isinstance(self.value, list) or len(self.value) != n:
            raise self.error(what)
        return tuple(child.as_float(positive=positive) for child in self.items())

    def as_interval(self) -> tuple[float, float]:
        """``[lower, upper]`` with ``lower < upper``."""
        expected = "[lower, upper] with lower < upper"
        if not isinstance(self.value, list) or len(self.value) != 2:
            raise self.error(expected)
        lo, hi = (child.as_float() for child in self.items())
        if not lo < hi:
            raise self.error(expected)
        return lo, hi


def yaml_name(name: str) -> str:
    """``name`` as a YAML scalar that reads back as the same string (quoted when YAML 1.1
    would read it as something else: ``on``, ``no``, ``1e3``, ``null``, ...)."""
    plain = yaml.safe_load(name) if name.strip() == name and name else None
    return name if isinstance(plain, str) and plain == name else "'" + name.replace("'", "''") + "'"


def _number(value: object) -> float | None:
    """A YAML number; also the strings YAML 1.1 leaves unparsed, such as ``1e-3``."""
    if isinstance(value, bool):
        return None
    if isinstance(value, int | float):
        return float(value)
    if isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            return None
    return None


MAX_DEPTH = 100
"""Collections nested deeper than this are rejected with a located error."""
_LINE_BREAK = re.compile("\r\n|[\r\n\x85\u2028\u2029]")  # YAML's line breaks


class _Loader(yaml.SafeLoader):
    """The safe loader with a nesting limit and located errors for values it cannot build."""

    def __init__(self, text: str) -> None:
        super().__init__(text)
        self._depth = 0

    def compose_node(self, parent: yaml.Node | None, index: int) -> yaml.Node | None:
        if self._depth >= MAX_DEPTH:
            raise yaml.composer.ComposerError(
                None,
                None,
                f"nesting deeper than {MAX_DEPTH} levels",
                self.peek_event().start_mark,  # type: ignore[no-untyped-call]
            )
        self._depth += 1
        try:
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def construct_object(self, node: yaml.Node, deep: bool = False) -> object:
        try:
            return super().construct_object(node, deep)
        except (ValueError, KeyError, TypeError, AttributeError, OverflowError) as exc:
            # An explicit tag the value does not fit, such as "!!int abc" or a bad timestamp.
            raise yaml.constructor.ConstructorError(
                None, None, f"cannot read {node.value!r} as {node.tag}: {exc}", node.start_mark
            ) from exc


def file_error(error_type: type[WorldFileError]) -> ErrorFactory:
    """An error factory for :func:`~sdar_tamp.textfile.read_text` raising ``error_type``."""

    def build(detail: str, file: str, location: SourceLocation | None) -> WorldFileError:
        return error_type(detail, location or SourceLocation(file, 1, 1))

    return build


def read_yaml(path: Path, error_type: type[WorldFileError]) -> Node:
    """Parse ``path`` into a root :class:`Node`; a missing file, bytes that are not UTF-8 or bad
    syntax raise ``error_type``."""
    return parse_yaml(read_text(path, file_error(error_type)), str(path), error_type)


def parse_yaml(text: str, name: str, error_type: type[WorldFileError]) -> Node:
    """Parse YAML text; ``name`` is the file name used in messages."""
    loader: _Loader | None = None
    try:
        loader = _Loader(text)  # checks the characters
        ynode = loader.get_single_node()
        value = loader.construct_document(ynode) if ynode is not None else None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        loc = SourceLocation(name, mark.line + 1, mark.column + 1) if mark else None
        raise error_type(f"invalid YAML: {exc.problem or exc.context}", loc) from exc
    except yaml.reader.ReaderError as exc:
        # Characters YAML does not allow (control characters); ``position`` indexes the text.
        breaks = list(_LINE_BREAK.finditer(text, 0, exc.position))
        line = len(breaks) + 1
        column = exc.position - (breaks[-1].end() if breaks else 0) + 1
        code = exc.character if isinstance(exc.character, int) else ord(exc.character)
        raise error_type(
            f"invalid YAML: character #x{code:04x} is not allowed; special characters must be "
            "escaped in double-quoted strings",
            SourceLocation(name, line, column),
        ) from exc
    except yaml.YAMLError as exc:
        raise error_type(f"invalid YAML: {exc}", SourceLocation(name, 1, 1)) from exc
    finally:
        if loader is not None:
            loader.dispose()
    return Node(value, "", name, ynode, error_type)
