"""Where the benchmark's runs execute: worker processes on this machine, or a Ray cluster.

A backend takes tasks and yields each with its answer (or a
:class:`~sdar_tamp.evaluation.workers.WorkerFailure`) as it finishes; the runner alone turns
answers into rows and writes them. Both backends

- bound a run by a hard limit [s], counted from the moment the run starts, and kill what
  overruns it (a failure with ``timed_out``);
- kill every run still going when the caller stops (an exception leaving the ``with`` block).

``process`` (:class:`~sdar_tamp.evaluation.workers.WorkerPool`): ``workers`` spawned processes
reading the instance files from the local disk. ``ray``
(:class:`~sdar_tamp.evaluation.ray_backend.RayBackend`): one Ray task per run, carrying the
instance as text, at most ``workers`` at once (default: one per CPU of the cluster).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from types import TracebackType
from typing import Protocol, TypeVar

from sdar_tamp.errors import ParameterError
from sdar_tamp.evaluation.ray_backend import BackendError, RayBackend
from sdar_tamp.evaluation.workers import WorkerFailure, WorkerPool

T = TypeVar("T")
R = TypeVar("R")

BACKENDS = ("process", "ray")
__all__ = ["BACKENDS", "Backend", "BackendError", "check_backend", "open_backend"]


class Backend(Protocol[T, R]):
    """Runs tasks and yields each with its answer, in the order they finish."""

    def __enter__(self) -> Backend[T, R]: ...

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None: ...

    def run(self, tasks: Iterable[T]) -> Iterator[tuple[T, R | WorkerFailure]]: ...


def check_backend(name: str, address: str | None = None) -> str:
    """``name`` if it is a backend, and ``address`` only with ``ray``; else
    :class:`ParameterError`."""
    if name not in BACKENDS:
        raise ParameterError(f"backend must be one of {', '.join(BACKENDS)}; got {name!r}")
    if address is not None and name != "ray":
        raise ParameterError(f"address is for the ray backend only (backend {name!r})")
    return name


def open_backend(
    name: str,
    fn: Callable[[T], R],
    workers: int | None,
    *,
    hard_limit: float | None,
    address: str | None = None,
) -> Backend[T, R]:
    """The backend ``name`` running ``fn`` (a picklable module-level function). ``workers``:
    runs at once (``None``: 1 for ``process``, one per cluster CPU for ``ray``); ``address``:
    the Ray cluster (``None``: ``$RAY_ADDRESS``, else a local Ray)."""
    check_backend(name, address)
    if name == "process":
        return WorkerPool(fn, workers or 1, hard_limit=hard_limit)
    return RayBackend(fn, workers, hard_limit=hard_limit, address=address)
