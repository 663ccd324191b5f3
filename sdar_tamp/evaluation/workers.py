"""Worker processes for the benchmark: one task at a time each, never outliving the parent.

:class:`WorkerPool` runs a picklable function on tasks in ``workers`` spawned processes and
yields each answer as it arrives. Unlike :class:`concurrent.futures.ProcessPoolExecutor` it
knows which process runs which task, so it can

- kill a worker whose task overruns a hard limit [s] and go on with a fresh one;
- report a worker that died (a crash, the out-of-memory killer) as a :class:`WorkerFailure` of
  that task only;
- kill every worker at once when the caller stops (an exception such as ``KeyboardInterrupt``
  leaving the ``with`` block).

A worker dies with its parent, even when the parent is killed with SIGKILL: on Linux the
kernel sends it SIGKILL (``prctl(PR_SET_PDEATHSIG)``); elsewhere a thread in the worker
notices within a second that its parent changed. Workers ignore SIGINT: Ctrl-C in a terminal
reaches the whole process group, and the parent alone decides what to do.
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import multiprocessing
import os
import signal
import sys
import threading
import time
import traceback
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from multiprocessing.connection import Connection, wait
from multiprocessing.process import BaseProcess
from types import TracebackType
from typing import Any, Generic, TypeVar

from sdar_tamp.errors import ParameterError

T = TypeVar("T")
R = TypeVar("R")

_PR_SET_PDEATHSIG = 1  # <linux/prctl.h>
_EXTERNAL = {signal.SIGTERM, signal.SIGINT, signal.SIGHUP}
_STOP = None  # sent to a worker: leave the loop
STARTUP_LIMIT = 120.0  # [s] a fresh worker may take to start its first task (imports)


@dataclass(frozen=True)
class WorkerFailure:
    """A task without an answer: the function raised, the worker died or overran the hard
    limit (``timed_out``). ``external``: the worker was terminated from outside (SIGTERM,
    SIGINT, SIGHUP; on Ray, its node died), so the task itself is not to blame."""

    reason: str
    external: bool = False
    timed_out: bool = False


def _follow_parent(parent_pid: int) -> None:
    """Make this process die when ``parent_pid`` (its parent) does."""
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        except (OSError, AttributeError):  # no prctl: the watching thread below remains
            pass
    if os.getppid() != parent_pid:  # the parent died before the line above
        os._exit(1)

    def watch() -> None:
        while os.getppid() == parent_pid:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, name="watch-parent", daemon=True).start()


def _block(signals: set[int], how: str = "block") -> set[int]:
    """Block, unblock or set (``how``) the calling thread's blocked ``signals``; returns the
    previous set (empty where the platform has no ``pthread_sigmask``)."""
    if not hasattr(signal, "pthread_sigmask"):
        return set()
    flag = {"block": signal.SIG_BLOCK, "unblock": signal.SIG_UNBLOCK, "set": signal.SIG_SETMASK}
    return {int(s) for s in signal.pthread_sigmask(flag[how], signals)}


@contextlib.contextmanager
def _signals_deferred(signals: tuple[int, ...]) -> Iterator[None]:
    """Hold back the Python handlers of ``signals`` for the block, then run what arrived.

    Blocking a signal in the calling thread is not enough: a signal sent to the process is
    taken by any thread that does not block it (e.g. a BLAS worker thread started at import),
    and Python then runs the handler in the main thread at its next bytecode, which may be
    in the middle of ``Process.start()``: a child spawned but not yet sent its start-up data
    would print ``EOFError: Ran out of input``. Only the main thread may set handlers;
    elsewhere the block runs as it is."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    previous = {s: signal.getsignal(s) for s in signals}
    for s in signals:
        signal.signal(s, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
        for s in dict.fromkeys(caught):
            signal.raise_signal(s)


def _serve(fn: Callable[[Any], Any], conn: Connection, parent_pid: int) -> None:
    """A worker's loop: receive a task, send ``("ok", answer)`` or ``("error", text)``."""
    _follow_parent(parent_pid)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _block({signal.SIGINT, signal.SIGTERM}, how="unblock")  # blocked by the parent at start
    while True:
        try:
            task = conn.recv()
        except (EOFError, OSError):
            return
        if task is _STOP:
            return
        conn.send(("started", None))
        try:
            reply: tuple[str, Any] = ("ok", fn(task))
        except Exception as error:
            reply = ("error", "".join(traceback.format_exception_only(error)).strip())
        try:
            conn.send(reply)
        except Exception as error:  # e.g. an answer that cannot be pickled
            conn.send(("error", f"cannot send the answer: {error!r}"))


@dataclass
class _Worker:
    process: BaseProcess
    conn: Connection


class _Working:
    """The answer of a worker that is still working."""


_WORKING = _Working()


@dataclass
class _Job(Generic[T]):
    worker: _Worker
    task: T
    deadline: float  # [s] on the monotonic clock; inf without a hard limit


def _death(process: BaseProcess) -> WorkerFailure:
    code = process.exitcode
    if code is not None and code < 0:
        name = signal.Signals(-code).name
        return WorkerFailure(f"worker process killed by {name}", -code in _EXTERNAL)
    return WorkerFailure(f"worker process ended without an answer (exit code {code})")


class WorkerPool(Generic[T, R]):
    """``workers`` spawned processes running ``fn`` (a picklable, module-level function).

    Use it as a context manager: leaving the block normally lets idle workers end; leaving it
    by an exception kills them all at once. ``hard_limit`` [s] (default: none) bounds the time
    a worker may take for one task before it is killed and replaced."""

    def __init__(
        self,
        fn: Callable[[T], R],
        workers: int,
        *,
        hard_limit: float | None = None,
        poll: float = 0.5,
    ) -> None:
        if workers < 1:
            raise ParameterError(f"workers must be >= 1, got {workers}")
        if hard_limit is not None and not hard_limit > 0:
            raise ParameterError(f"hard limit must be > 0 [s] or None, got {hard_limit}")
        self.fn = fn
        self.workers = workers
        self.hard_limit = hard_limit
        self.poll = poll
        self._context = multiprocessing.get_context("spawn")
        self._live: list[_Worker] = []

    @property
    def pids(self) -> list[int]:
        """Process ids of the live workers."""
        return [w.process.pid for w in list(self._live) if w.process.pid is not None]

    def __enter__(self) -> WorkerPool[T, R]:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.close(kill=kind is not None)

    def _start(self) -> _Worker:
        mine, theirs = self._context.Pipe(duplex=True)
        process = self._context.Process(
            target=_serve, args=(self.fn, theirs, os.getpid()), name="sdar-worker", daemon=True
        )
        # The new process inherits SIGINT and SIGTERM blocked, and ignores SIGINT before it
        # unblocks them: a Ctrl-C while it starts up reaches the parent only, and a signal to
        # the parent waits until the new worker is on the list that close() kills.
        # A signal that reaches the parent meanwhile is handled once the worker is listed.
        with _signals_deferred((signal.SIGINT, signal.SIGTERM)):
            blocked = _block({signal.SIGINT, signal.SIGTERM})
            try:
                process.start()
                worker = _Worker(process, mine)
                self._live.append(worker)
            finally:
                _block(blocked, how="set")
        theirs.close()
        return worker

    def _discard(self, worker: _Worker, kill: bool) -> None:
        if kill and worker.process.is_alive():
            worker.process.kill()
        worker.process.join(timeout=10.0)
        worker.conn.close()
        self._live.remove(worker)

    def close(self, kill: bool = False) -> None:
        """End every worker: ask the idle ones to stop, or (``kill``) kill them all."""
        for worker in list(self._live):
            if not kill:
                try:
                    worker.conn.send(_STOP)
                    worker.process.join(timeout=10.0)
                except OSError:
                    pass
            self._discard(worker, kill=True)

    def run(self, tasks: Iterable[T]) -> Iterator[tuple[T, R | WorkerFailure]]:
        """Each task with its answer (or failure), in the order they finish. The hard limit
        counts from the moment a worker starts the task (a fresh worker may first take up to
        :data:`STARTUP_LIMIT` more to start)."""
        pending = deque(tasks)
        idle: list[_Worker] = []
        busy: list[_Job[T]] = []
        while pending or busy:
            while pending and (idle or len(busy) < self.workers):
                worker = idle.pop() if idle else self._start()
                task = pending.popleft()
                try:
                    worker.conn.send(task)
                except OSError:  # it died while idle: a fresh one takes the task
                    self._discard(worker, kill=True)
                    pending.appendleft(task)
                    continue
                deadline = math.inf  # until the worker says it started: time to start up
                if self.hard_limit is not None:
                    deadline = time.monotonic() + max(self.hard_limit, STARTUP_LIMIT)
                busy.append(_Job(worker, task, deadline))
            first = min(job.deadline for job in busy)
            timeout = max(0.0, min(self.poll, first - time.monotonic()))
            handles: list[Any] = [job.worker.conn for job in busy]
            handles += [job.worker.process.sentinel for job in busy]
            wait(handles, timeout)
            for job in list(busy):
                answer = self._answer(job)
                if isinstance(answer, _Working):
                    continue
                busy.remove(job)
                if job.worker in self._live:
                    idle.append(job.worker)
                yield job.task, answer

    def _answer(self, job: _Job[T]) -> R | WorkerFailure | _Working:
        """The worker's answer, a failure, or :data:`_WORKING` while it is still working. A
        worker that died or overran the hard limit is discarded."""
        worker = job.worker
        while worker.conn.poll():
            try:
                kind, value = worker.conn.recv()
            except (EOFError, OSError):
                worker.process.join(timeout=10.0)
                self._discard(worker, kill=True)
                return _death(worker.process)
            if kind == "started":
                if self.hard_limit is not None:
                    job.deadline = time.monotonic() + self.hard_limit
                continue
            if kind == "ok":
                answer: R = value
                return answer
            return WorkerFailure(str(value))
        if not worker.process.is_alive():
            self._discard(worker, kill=True)
            return _death(worker.process)
        if time.monotonic() > job.deadline:
            self._discard(worker, kill=True)
            return WorkerFailure(
                f"no answer within the hard limit of {self.hard_limit:g} s: worker killed",
                timed_out=True,
            )
        return _WORKING
