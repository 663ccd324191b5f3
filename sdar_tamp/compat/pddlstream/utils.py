"""``pddlstream.utils``: the small helpers PDDLStream programs import (files, strings, timing).

Written from their documented behaviour; each does what a program relying on its result
expects (``read`` returns the file's text, ``safe_zip`` refuses sequences of different
lengths, ``str_from_object`` prints containers with sorted sets and dictionaries, ...).
"""

from __future__ import annotations

import cProfile
import io
import itertools
import math
import os
import pstats
import random
import shutil
import time
from collections import Counter, defaultdict
from collections.abc import Callable, Hashable, Iterable, Iterator, Sequence
from types import TracebackType
from typing import Any

from sdar_tamp.compat.pddlstream.unsupported import not_provided
from sdar_tamp.errors import ParameterError
from sdar_tamp.language.generators import negate_test as negate_test
from sdar_tamp.textfile import decode_text

__all__ = [
    "INF",
    "SEPARATOR",
    "Profiler",
    "Verbose",
    "apply_mapping",
    "clear_dir",
    "elapsed_time",
    "ensure_dir",
    "find",
    "find_unique",
    "flatten",
    "get_file_path",
    "get_mapping",
    "implies",
    "inclusive_range",
    "inf_generator",
    "int_ceil",
    "irange",
    "is_hashable",
    "negate_test",
    "neighbors_from_orders",
    "randomize",
    "read",
    "read_pddl",
    "safe_apply_mapping",
    "safe_rm_dir",
    "safe_zip",
    "sorted_str_from_list",
    "str_eq",
    "str_from_object",
    "user_input",
    "value_or_id",
    "write",
]

INF = math.inf
SEPARATOR = "\n" + 80 * "-" + "\n"
inf_generator = itertools.count


def read(filename: str | os.PathLike[str]) -> str:
    """The text of the UTF-8 file ``filename``. A missing file raises ``OSError`` as the
    original does; bytes that are not UTF-8 raise :class:`~sdar_tamp.textfile.TextFileError`
    at ``file:line:col`` with the byte offset."""
    with open(filename, "rb") as handle:
        data = handle.read()
    return decode_text(data, os.fspath(filename))


def write(filename: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` to ``filename`` (only where the program asks for it)."""
    with open(filename, "w", encoding="utf-8") as handle:
        handle.write(text)


def get_file_path(file: str, rel_path: str) -> str:
    """``rel_path`` relative to the folder of ``file`` (usually a module's ``__file__``)."""
    return os.path.join(os.path.dirname(os.path.abspath(file)), rel_path)


def read_pddl(this_file: str, pddl_filename: str) -> str:
    """The text of ``pddl_filename`` next to ``this_file``."""
    return read(get_file_path(this_file, pddl_filename))


def user_input(prompt: str = "") -> str:
    """``input(prompt)``; at the end of input (a closed or redirected stdin, as in a batch run)
    it returns ``""`` instead of raising, so a program's "Continue?" pauses do not stop it."""
    try:
        return input(prompt)
    except EOFError:
        print()
        return ""


def elapsed_time(start_time: float) -> float:
    """Seconds since ``start_time`` (a ``time.time()`` value)."""
    return time.time() - start_time


def safe_zip(sequence1: Sequence[Any], sequence2: Sequence[Any]) -> Iterator[tuple[Any, Any]]:
    """``zip`` of two sequences of the same length (else ``ValueError``)."""
    if len(sequence1) != len(sequence2):
        raise ValueError(
            f"safe_zip: sequences of different lengths ({len(sequence1)} and {len(sequence2)})"
        )
    return zip(sequence1, sequence2, strict=True)


def get_mapping(sequence1: Sequence[Any], sequence2: Sequence[Any]) -> dict[Any, Any]:
    return dict(safe_zip(sequence1, sequence2))


def apply_mapping(sequence: Iterable[Any], mapping: dict[Any, Any]) -> tuple[Any, ...]:
    return tuple(mapping.get(item, item) for item in sequence)


def safe_apply_mapping(sequence: Iterable[Any], mapping: dict[Any, Any]) -> tuple[Any, ...]:
    return tuple(mapping[item] for item in sequence)


def flatten(iterable_of_iterables: Iterable[Iterable[Any]]) -> Iterator[Any]:
    return (item for iterable in iterable_of_iterables for item in iterable)


def find(test: Callable[[Any], Any], sequence: Iterable[Any]) -> Any:
    """The first item passing ``test``, else None."""
    return next((item for item in sequence if test(item)), None)


def find_unique(test: Callable[[Any], Any], sequence: Iterable[Any]) -> Any:
    """The one item passing ``test``; ``RuntimeError`` if none or several do."""
    found = [item for item in sequence if test(item)]
    if len(found) != 1:
        raise RuntimeError(f"expected exactly one element passing the test, found {len(found)}")
    return found[0]


def implies(a: Any, b: Any) -> bool:
    return bool(not a or b)


def irange(start: float, end: float | None = None, step: float = 1) -> Iterator[float]:
    """``range`` that also accepts ``end=INF`` (and floats)."""
    if end is None:
        start, end = 0, start
    value = start
    while value < end:
        yield value
        value += step


def inclusive_range(start: float, stop: float, step: float = 1) -> list[float]:
    """``start, start + step, ...`` below ``stop``, plus ``stop`` when it falls on the grid."""
    if step <= 0:
        raise ParameterError(f"inclusive_range: step must be > 0, got {step}")
    values = []
    count = 0
    while start + count * step < stop:
        values.append(start + count * step)
        count += 1
    if math.isclose(start + count * step, stop) or (values and values[-1] == stop):
        values.append(stop)
    return values


def randomize(iterable: Iterable[Any]) -> list[Any]:
    """The items in a random order (Python's global ``random``, as PDDLStream does)."""
    sequence = list(iterable)
    random.shuffle(sequence)
    return sequence


def str_eq(s1: str, s2: str, ignore_case: bool = True) -> bool:
    return s1.lower() == s2.lower() if ignore_case else s1 == s2


def is_hashable(value: Any) -> bool:
    if not isinstance(value, Hashable):
        return False
    try:
        hash(value)
    except TypeError:
        return False
    return True


def value_or_id(value: Any) -> Any:
    """``value`` itself when hashable, else its ``id``."""
    return value if is_hashable(value) else id(value)


def str_from_object(obj: Any, ndigits: int | None = None) -> str:
    """A stable printable form: containers recursively, sets and dict keys sorted, floats
    rounded to ``ndigits`` when given."""

    def text(item: Any) -> str:
        return str_from_object(item, ndigits)

    kind = type(obj)
    if kind is list:
        return "[" + ", ".join(map(text, obj)) + "]"
    if kind is tuple:
        return "(" + ", ".join(map(text, obj)) + ")"
    if kind in (dict, defaultdict, Counter):
        keys = sorted(obj, key=text)
        return "{" + ", ".join(f"{text(k)}: {text(obj[k])}" for k in keys) + "}"
    if kind in (set, frozenset):
        return "{" + ", ".join(sorted(map(text, obj))) + "}"
    if ndigits is not None and isinstance(obj, float):
        obj = round(obj, ndigits)
    return repr(obj)


def sorted_str_from_list(obj: Iterable[Any], ndigits: int | None = None) -> str:
    return "[" + ", ".join(sorted(str_from_object(item, ndigits) for item in obj)) + "]"


def ensure_dir(path: str) -> None:
    """Create the folder of ``path`` (the part before the last separator) if missing."""
    directory = os.path.dirname(path)
    if directory:
        os.makedirs(directory, exist_ok=True)


def safe_rm_dir(directory: str) -> None:
    """Remove ``directory`` and its contents if it exists."""
    if os.path.exists(directory):
        shutil.rmtree(directory)


def clear_dir(directory: str) -> None:
    safe_rm_dir(directory)
    os.makedirs(directory, exist_ok=True)


class Profiler:
    """``with Profiler(field="tottime", num=10): ...`` profiles the block and prints the
    ``num`` most expensive functions sorted by ``field`` (``tottime`` or ``cumtime``)."""

    fields = ("tottime", "cumtime")

    def __init__(self, field: str = "tottime", num: int | None = 10) -> None:
        if field not in self.fields:
            raise ParameterError(f"Profiler field must be one of {self.fields}, got {field!r}")
        self.field = field
        self.num = num
        self.profile = cProfile.Profile()

    def __enter__(self) -> cProfile.Profile:
        self.profile.enable()
        return self.profile

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.profile.disable()
        if self.num is None:
            return
        out = io.StringIO()
        pstats.Stats(self.profile, stream=out).sort_stats(self.field).print_stats(self.num)
        print(out.getvalue())


class Verbose:
    """``with Verbose(False): ...`` silences ``print`` output of the block."""

    def __init__(self, verbose: bool = False) -> None:
        self.verbose = verbose
        self._redirect: Any = None

    def __enter__(self) -> Verbose:
        if not self.verbose:
            import contextlib

            self._redirect = contextlib.redirect_stdout(io.StringIO())
            self._redirect.__enter__()
        return self

    def __exit__(self, *exc: Any) -> None:
        if self._redirect is not None:
            self._redirect.__exit__(*exc)
            self._redirect = None


def int_ceil(value: float) -> int:
    return math.ceil(value)


def neighbors_from_orders(orders: Iterable[tuple[Any, Any]]) -> tuple[dict[Any, set[Any]], ...]:
    """``(incoming, outgoing)`` adjacency sets of a set of ``(before, after)`` pairs."""
    incoming: dict[Any, set[Any]] = defaultdict(set)
    outgoing: dict[Any, set[Any]] = defaultdict(set)
    for before, after in orders:
        incoming[after].add(before)
        outgoing[before].add(after)
    return incoming, outgoing


__getattr__ = not_provided(
    __name__,
    (
        "PDDLStream's helpers for its own internals (memory checks, timers over Fast "
        "Downward, graph helpers) are not provided"
    ),
)
