"""Checks of argument values, shared by the Python API and the ``sdar`` command line.

A numeric rule (:class:`Real`, :class:`Integer`) has two uses:

* ``rule.check("max_time", value)`` in an API function returns the value or raises
  :class:`~sdar_tamp.errors.ParameterError` naming the parameter and the valid range;
* ``type=rule.parse`` in an ``argparse`` option turns the text into the value or makes the
  parser exit with ``argument --time-limit: expected a finite number > 0 [s], got 'nan'``.

:func:`output_file` and :func:`output_folder` check where a command may write before it does
any work. This module imports nothing of the project but :mod:`sdar_tamp.errors`.
"""

from __future__ import annotations

import argparse
import math
import numbers
import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from sdar_tamp.errors import ParameterError

__all__ = [
    "COST_BOUND",
    "COUNT",
    "FPS",
    "MAX_TIME",
    "SEARCH_WEIGHT",
    "SEED",
    "TIME_LIMIT",
    "Integer",
    "Real",
    "optional",
    "output_file",
    "output_folder",
]


@dataclass(frozen=True)
class Real:
    """A real number ``> low`` (``>= low`` when ``closed``), finite unless ``allow_inf`` (where
    ``inf`` means "no limit"). NaN and booleans are always refused."""

    low: float = 0.0
    closed: bool = False
    allow_inf: bool = False
    unit: str = ""

    def describe(self) -> str:
        bound = f"{'>=' if self.closed else '>'} {self.low:g}"
        unit = f" [{self.unit}]" if self.unit else ""
        if self.allow_inf:
            return f"a number {bound}{unit} or inf"
        return f"a finite number {bound}{unit}"

    def accepts(self, value: float) -> bool:
        if math.isnan(value) or (math.isinf(value) and not (self.allow_inf and value > 0)):
            return False
        return value >= self.low if self.closed else value > self.low

    def check(self, name: str, value: object) -> float:
        """``value`` as a float, or :class:`ParameterError` naming ``name``."""
        if (
            isinstance(value, bool)
            or not isinstance(value, numbers.Real)
            or not self.accepts(float(value))
        ):
            raise ParameterError(f"{name} must be {self.describe()}, got {value!r}")
        return float(value)

    def parse(self, text: str) -> float:
        """``argparse`` type: the number in ``text``, or :class:`argparse.ArgumentTypeError`."""
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not self.accepts(value):
            raise argparse.ArgumentTypeError(f"expected {self.describe()}, got {text!r}")
        return value


@dataclass(frozen=True)
class Integer:
    """An integer ``>= low`` (booleans and floats are refused, also ``3.0``)."""

    low: int = 0

    def describe(self) -> str:
        return f"an integer >= {self.low}"

    def check(self, name: str, value: object) -> int:
        """``value`` as an int, or :class:`ParameterError` naming ``name``."""
        if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < self.low:
            raise ParameterError(f"{name} must be {self.describe()}, got {value!r}")
        return int(value)

    def parse(self, text: str) -> int:
        """``argparse`` type: the integer in ``text``, or :class:`argparse.ArgumentTypeError`."""
        try:
            value = int(text)
        except ValueError:
            value = self.low - 1
        if value < self.low:
            raise argparse.ArgumentTypeError(f"expected {self.describe()}, got {text!r}")
        return value


def optional(rule: Real, name: str, value: float | None) -> float | None:
    """``None`` (not given), or ``rule.check(name, value)``."""
    return None if value is None else rule.check(name, value)


#: A time limit given on the command line [s]: finite and positive.
TIME_LIMIT = Real(0.0, unit="s")
#: A time budget of the API [s]: positive; ``inf`` means none.
MAX_TIME = Real(0.0, allow_inf=True, unit="s")
#: A bound on plan cost or on a count of iterations: >= 0, ``inf`` means none.
COST_BOUND = Real(0.0, closed=True, allow_inf=True)
#: Frames per second of plan time [1/s].
FPS = Real(0.0, unit="1/s")
#: The weight of weighted A*.
SEARCH_WEIGHT = Real(1.0, closed=True)
#: A time within a plan [s]: finite and >= 0.
PLAN_TIME = Real(0.0, closed=True, unit="s")
#: A random seed.
SEED = Integer(0)
#: A number of things (objects, workers, ...).
COUNT = Integer(1)


# -- output paths -------------------------------------------------------------------------------
def output_file(
    path: Path | str,
    *,
    name: str = "--output",
    suffixes: Iterable[str] | None = None,
    force: bool = False,
) -> Path:
    """Check that a command may write the file ``path`` and return it.

    Refused: a suffix not in ``suffixes`` (compared in lower case; ``None``: any), an existing
    folder, an existing file unless ``force``, and a path whose nearest existing ancestor is
    not a writable folder. Missing parent folders are fine (the writers create them)."""
    path = Path(path)
    if suffixes is not None:
        allowed = tuple(suffixes)
        if path.suffix.lower() not in allowed:
            raise ParameterError(
                f"{name}: expected a file ending in {', '.join(allowed)}, got {str(path)!r}"
            )
    if path.is_dir():
        raise ParameterError(f"{name}: expected a file, {str(path)!r} is a folder")
    if path.exists() and not force:
        raise ParameterError(
            f"{name}: {str(path)!r} exists; pass --force to replace it, or choose another name"
        )
    _check_writable_folder(path.parent, path, name)
    return path


def output_folder(path: Path | str, *, name: str = "--output") -> Path:
    """Check that a command may write files into the folder ``path`` (created if missing)."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise ParameterError(f"{name}: expected a folder, {str(path)!r} is a file")
    _check_writable_folder(path, path, name)
    return path


def _check_writable_folder(folder: Path, target: Path, name: str) -> None:
    """The nearest existing ancestor of ``folder`` (itself included) is a writable folder;
    ``target`` is the path named in the message."""
    probe = folder.absolute()
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    if not probe.is_dir():
        raise ParameterError(
            f"{name}: cannot write {str(target)!r}: {str(probe)!r} is a file, not a folder"
        )
    if not os.access(probe, os.W_OK | os.X_OK):
        raise ParameterError(
            f"{name}: cannot write {str(target)!r}: no permission to write in {str(probe)!r}"
        )
