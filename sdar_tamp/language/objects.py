"""The table between arbitrary Python values and the object names solvers see.

Hashable values are the same object when they are equal (by value); unhashable ones (numpy
arrays, lists) are the same object only when they are the same Python object (by identity).
Values from the ``constant_map`` keep their constant's name; every other value is named
``#v<k>`` in order of first appearance, which no PDDL name can collide with.
"""

from __future__ import annotations

from collections.abc import Hashable, Mapping
from typing import Any


def _key(value: Any) -> tuple[str, Any]:
    if isinstance(value, Hashable):
        try:
            hash(value)
        except TypeError:  # a tuple holding something unhashable
            return ("id", id(value))
        return ("value", (type(value) is bool, value))
    return ("id", id(value))


def keyed_by_identity(value: Any) -> bool:
    """Is ``value`` named by identity (unhashable: it may change while it keeps its name)?"""
    return _key(value)[0] == "id"


class ObjectTable:
    """Assigns names to values and gives the values back."""

    def __init__(self, constants: Mapping[str, Any] | None = None) -> None:
        self._names: dict[tuple[str, Any], str] = {}
        self._values: dict[str, Any] = {}
        self._keep: list[Any] = []  # keeps identity-keyed values alive so ids stay unique
        for name, value in (constants or {}).items():
            self._names.setdefault(_key(value), name)
            self._values[name] = value
            self._keep.append(value)

    def name(self, value: Any) -> str:
        """The object name of ``value``, creating one on first sight."""
        key = _key(value)
        found = self._names.get(key)
        if found is None:
            found = f"#v{len(self._values)}"
            self._names[key] = found
            self._values[found] = value
            self._keep.append(value)
        return found

    def copy(self) -> ObjectTable:
        """An independent table with the same names so far (one per solve keeps runs alike)."""
        other = ObjectTable()
        other._names = dict(self._names)
        other._values = dict(self._values)
        other._keep = list(self._keep)
        return other

    def value(self, name: str) -> Any:
        """The Python value behind ``name``."""
        return self._values[name]

    def __contains__(self, name: object) -> bool:
        return name in self._values

    def names(self) -> tuple[str, ...]:
        return tuple(self._values)
