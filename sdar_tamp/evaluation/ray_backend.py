"""The ``ray`` backend of the benchmark: one Ray task per run, on this machine or a cluster.

Ray is an optional dependency (``pip install 'sdar-tamp[cluster]'``), imported when the
backend starts; this module is its typed adapter (Ray is used as an untyped module).

- Where: ``address`` (``host:port`` of the cluster's head, as printed by ``ray start --head``;
  ``auto``: the cluster this machine belongs to), else ``$RAY_ADDRESS``, else a local Ray
  started for the benchmark with ``workers`` CPUs (and shut down after it). A ``host:port``
  is first probed over TCP, so an unreachable cluster is an error within seconds instead of
  Ray's long retries. A Ray the caller already initialised is used as it is.
- At most ``workers`` tasks at once (default: the cluster's CPUs), one CPU each.
- Each task is a generator: it reports that it started, then its answer. The hard limit
  counts from the start, like the process backend's, and an overrunning task is cancelled
  with ``ray.cancel(force=True)`` (its worker process is killed). A task that has not started
  after the hard limit (at least :data:`STARTUP_LIMIT`) is cancelled too, not recorded.
- A task whose node died, or that failed before it started, is reported as ``external`` (not
  the run's fault: a rerun runs it); every other Ray error is a failure of that run. A task
  that cannot even be unpacked on its node (``sdar_tamp`` missing there) stops the sweep with
  :class:`BackendError`: the cluster needs fixing, not thousands of error rows.
"""

from __future__ import annotations

import importlib
import logging
import math
import os
import re
import signal
import socket
import threading
import time
import traceback
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from types import TracebackType
from typing import Any, Generic, TypeVar
from urllib.parse import urlsplit

from sdar_tamp.errors import ParameterError, SdarError
from sdar_tamp.evaluation.workers import STARTUP_LIMIT, WorkerFailure

T = TypeVar("T")
R = TypeVar("R")

log = logging.getLogger(__name__)

PROBE_TIMEOUT = 5.0  # [s] to open a TCP connection to the cluster's address
_EXTERNAL_ERRORS = ("NodeDiedError", "LocalRayletDiedError", "OwnerDiedError")
_ANSI = re.compile(r"\x1b\[[0-9;]*m")


class BackendError(SdarError):
    """A backend that cannot start: Ray missing, a cluster address that cannot be reached."""


def import_ray() -> Any:
    """The ``ray`` module, or :class:`BackendError` saying how to install it."""
    try:
        return importlib.import_module("ray")
    except ImportError as error:
        raise BackendError(
            f"the ray backend needs Ray ({error}): pip install 'sdar-tamp[cluster]'"
        ) from None


def cluster_address(address: str | None) -> str | None:
    """The address to connect to: ``address``, else ``$RAY_ADDRESS``; ``None``: a local Ray."""
    chosen = address if address is not None else os.environ.get("RAY_ADDRESS") or None
    return None if chosen in (None, "local") else chosen


def probe(address: str, timeout: float = PROBE_TIMEOUT) -> None:
    """Raise :class:`BackendError` unless a TCP connection to ``address`` (``host:port`` or
    ``ray://host:port``) opens within ``timeout`` [s]; ``auto`` is left to Ray."""
    if address == "auto":
        return
    parts = urlsplit(address if "://" in address else f"//{address}")
    try:
        host, port = parts.hostname, parts.port
    except ValueError:
        host, port = None, None
    if not host or port is None:
        raise ParameterError(
            f"address must be host:port (the head's address, e.g. 10.0.0.1:6379), "
            f"ray://host:port or auto; got {address!r}"
        )
    try:
        socket.create_connection((host, port), timeout=timeout).close()
    except OSError as error:
        raise BackendError(
            f"cannot reach the Ray cluster at {address} ({error.strerror or error}); "
            "check the address (`ray status` on the head prints it) and that the head runs"
        ) from None


def _call(fn: Callable[[Any], Any], task: Any) -> Iterator[tuple[str, Any]]:
    """The Ray task: ``("started", None)``, then ``("ok", answer)`` or ``("error", text)``."""
    yield "started", None
    try:
        answer = fn(task)
    except Exception as error:
        yield "error", "".join(traceback.format_exception_only(error)).strip()
    else:
        yield "ok", answer


def describe(error: BaseException) -> str:
    """``Name: first line`` of the innermost exception a Ray error wraps."""
    inner = error
    for _ in range(8):
        cause = getattr(inner, "cause", None)
        if not isinstance(cause, BaseException) and inner.args:
            cause = inner.args[0]
        if not isinstance(cause, BaseException) or cause is inner:
            break
        inner = cause
    lines = _ANSI.sub("", str(inner)).strip().splitlines()
    return f"{type(inner).__name__}: {lines[0]}" if lines else type(inner).__name__


@dataclass
class _Job(Generic[T]):
    task: T
    deadline: float  # [s] on the monotonic clock
    started: bool = False


class _Working:
    """The answer of a task still running."""


_WORKING = _Working()


class RayBackend(Generic[T, R]):
    """Ray tasks running ``fn`` (a module-level function importable on every node)."""

    def __init__(
        self,
        fn: Callable[[T], R],
        workers: int | None,
        *,
        hard_limit: float | None = None,
        address: str | None = None,
        poll: float = 0.5,
    ) -> None:
        if workers is not None and workers < 1:
            raise ParameterError(f"workers must be >= 1 or None, got {workers}")
        if hard_limit is not None and not hard_limit > 0:
            raise ParameterError(f"hard limit must be > 0 [s] or None, got {hard_limit}")
        self.fn = fn
        self.workers = workers
        self.hard_limit = hard_limit
        self.address = cluster_address(address)
        self.poll = poll
        self._module = import_ray()
        if self.address is not None and not self._module.is_initialized():
            probe(self.address)  # here, so that nothing is written for a cluster not there
        self._ray: Any = None  # the module while the backend is open
        self._owned = False  # this backend initialised Ray, so it shuts it down
        self._jobs: dict[Any, _Job[T]] = {}  # ObjectRefGenerator -> job

    def __enter__(self) -> RayBackend[T, R]:
        ray = self._module
        if not ray.is_initialized():
            self._init(ray)
            self._owned = True
        self._ray = ray
        return self

    def _init(self, ray: Any) -> None:
        # ray.init replaces the SIGTERM handler (with sys.exit); the caller's stays.
        main = threading.current_thread() is threading.main_thread()
        handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)} if main else {}
        options: dict[str, Any] = dict(configure_logging=False, log_to_driver=False)
        try:
            if self.address is None:
                ray.init(address="local", num_cpus=self.workers, include_dashboard=False, **options)
            else:
                ray.init(address=self.address, **options)
        except Exception as error:  # Ray raises many kinds here; all mean "no cluster"
            where = self.address or "a local Ray"
            raise BackendError(f"cannot start Ray on {where}: {error}") from None
        finally:
            for s, handler in handlers.items():
                signal.signal(s, handler)

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.close()

    def close(self) -> None:
        """Cancel (kill) every task still running; shut Ray down if this backend started it."""
        ray, self._ray = self._ray, None
        if ray is None:
            return
        for gen in list(self._jobs):
            self._cancel(ray, gen)
        self._jobs.clear()
        if self._owned:
            ray.shutdown()
            self._owned = False

    @staticmethod
    def _cancel(ray: Any, gen: Any) -> None:
        try:
            ray.cancel(gen, force=True)
        except Exception as error:  # already finished or its node is gone: nothing to kill
            log.debug("cancel: %r", error)

    def capacity(self) -> int:
        """Tasks at once: ``workers``, else the cluster's CPUs (at least 1)."""
        if self.workers is not None:
            return self.workers
        return max(1, int(self._ray.cluster_resources().get("CPU", 1)))

    def run(self, tasks: Iterable[T]) -> Iterator[tuple[T, R | WorkerFailure]]:
        """Each task with its answer (or failure), in the order they finish."""
        ray = self._ray
        if ray is None:
            raise RuntimeError("RayBackend.run outside its with block")
        remote = ray.remote(num_cpus=1, max_retries=0)(_call).options(num_returns="streaming")
        capacity = self.capacity()
        pending = deque(tasks)
        while pending or self._jobs:
            while pending and len(self._jobs) < capacity:
                task = pending.popleft()
                gen = remote.remote(self.fn, task)
                self._jobs[gen] = _Job(task, self._deadline(STARTUP_LIMIT))
            first = min(job.deadline for job in self._jobs.values())
            timeout = max(0.0, min(self.poll, first - time.monotonic()))
            ray.wait(list(self._jobs), num_returns=1, timeout=timeout)
            for gen, job in list(self._jobs.items()):
                answer = self._answer(ray, gen, job)
                if isinstance(answer, _Working):
                    continue
                del self._jobs[gen]
                yield job.task, answer

    def _deadline(self, at_least: float = 0.0) -> float:
        if self.hard_limit is None:
            return math.inf
        return time.monotonic() + max(self.hard_limit, at_least)

    def _answer(self, ray: Any, gen: Any, job: _Job[T]) -> R | WorkerFailure | _Working:
        """The task's answer, a failure, or :data:`_WORKING`; an overrunning task is killed."""
        while ray.wait([gen], num_returns=1, timeout=0)[0]:
            try:
                kind, value = ray.get(next(gen))
            except StopIteration:
                return WorkerFailure("the Ray task ended without an answer")
            except ray.exceptions.RayError as error:
                if not job.started and isinstance(error, ray.exceptions.RayTaskError):
                    raise BackendError(
                        f"a Ray task could not start on its node ({describe(error)}); every "
                        "node needs the same sdar-tamp and ray versions as this machine "
                        "(pip install 'sdar-tamp[cluster]')"
                    ) from None
                external = not job.started or type(error).__name__ in _EXTERNAL_ERRORS
                return WorkerFailure(f"Ray task failed: {describe(error)}", external)
            if kind == "started":
                job.started = True
                job.deadline = self._deadline()
                continue
            if kind == "ok":
                answer: R = value
                return answer
            return WorkerFailure(str(value))
        if time.monotonic() > job.deadline:
            self._cancel(ray, gen)
            if not job.started:  # queued all along (a busy or shrunk cluster): not its fault
                waited = max(self.hard_limit or 0.0, STARTUP_LIMIT)
                return WorkerFailure(f"the Ray task did not start within {waited:g} s", True)
            return WorkerFailure(
                f"no answer within the hard limit of {self.hard_limit:g} s: Ray task killed",
                timed_out=True,
            )
        return _WORKING
