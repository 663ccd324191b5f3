"""Loading the classical planner's numba code: whether numba can run here (:func:`available`),
compiling a kernel (:func:`compile_kernel`) and the compressed rows the kernels read.

The kernels are the relaxed heuristics (:mod:`.jit_relaxed`) and the successor generator's trie
walk (:mod:`.jit_successors`). numba is imported only when this code is first needed (it is a
dependency, but a platform without a numba wheel still plans with the other engines:
:func:`available` says whether it loads; code that fails to load or compile is reported once and
not tried again in the process). The machine code is cached beside the kernels' modules (or in
numba's user-wide cache where that folder is not writable), so only the first process compiles
it (about 2 s).
"""

from __future__ import annotations

import importlib.util
from typing import Any

import numpy as np
import numpy.typing as npt

from solvers.classical.errors import BackendUnavailableError

IntArray = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]


_broken: list[str] = []  # why compiled code failed in this process, if it did


def available() -> bool:
    """Whether numba is installed and its code has not failed in this process."""
    return not _broken and importlib.util.find_spec("numba") is not None


def why_unavailable() -> str:
    """Why :func:`available` is False (for an error message)."""
    if _broken:
        return f"numba failed in this process ({_broken[0]})"
    return "numba is not installed: pip install numba"


def mark_unavailable(what: str, error: Exception) -> CompiledCodeUnavailable:
    _broken.append(f"{what}: {error}")
    return CompiledCodeUnavailable(f"numba cannot run {what}: {error}")


class CompiledCodeUnavailable(BackendUnavailableError):
    """numba is installed but its code cannot be loaded or compiled here (a search that
    switches to compiled code mid-way goes on with the Python engines instead)."""


def compile_kernel(function: Any) -> Any:
    """``function`` compiled by numba (or loaded from its cache).

    Raises:
        CompiledCodeUnavailable: numba cannot load or compile it here.
    """
    try:
        import numba  # a heavy import: only for tasks that use this engine

        return numba.njit(cache=True, nogil=True)(function)
    except Exception as error:  # a broken numba or llvmlite install, an unsupported platform
        raise mark_unavailable(function.__name__, error) from error


def compressed_rows(rows: list[tuple[int, ...]]) -> tuple[IntArray, IntArray]:
    """Compressed rows: (start offsets, flat entries)."""
    start = np.zeros(len(rows) + 1, dtype=np.int64)
    start[1:] = np.cumsum([len(row) for row in rows])
    flat = np.fromiter((x for row in rows for x in row), dtype=np.int64, count=int(start[-1]))
    return start, flat
