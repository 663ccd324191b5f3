"""Typed, located reading of YAML documents.

:class:`Node` pairs a parsed value with its key path (``arms[1].joint_limits.elbow``) and its
place in the file, so every reader can raise an error that says where and what was expected.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import yaml

from sdar_tamp.errors import SourceLocation
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


def read_yaml(path: Path, error_type: type[WorldFileError]) -> Node:
    """Parse ``path`` into a root :class:`Node`; a missing file or bad syntax raises."""
    name = str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise error_type(f"cannot read file: {exc.strerror}", SourceLocation(name, 1, 1)) from exc
    return parse_yaml(text, name, error_type)


def parse_yaml(text: str, name: str, error_type: type[WorldFileError]) -> Node:
    """Parse YAML text; ``name`` is the file name used in messages."""
    try:
        ynode = yaml.compose(text, Loader=yaml.SafeLoader)
        value = yaml.safe_load(text)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark
        loc = SourceLocation(name, mark.line + 1, mark.column + 1) if mark else None
        raise error_type(f"invalid YAML: {exc.problem}", loc) from exc
    return Node(value, "", name, ynode, error_type)
