"""Calling user code (samplers, tests, functions) under the solve's time limit.

A user callable may block: a sampler that sleeps, spins or waits on a lock. Python cannot stop
a running call from outside, so :class:`CallRunner` offers two ways to honour ``max_time``:

- threaded (the default when the limit is finite): each call runs in one daemon worker thread
  while the solver's thread waits until the deadline (plus :data:`OVERRUN_TOLERANCE`). A call
  still running then is abandoned: the solve ends with a timeout on time, a warning names the
  call, and the worker finishes the call in the background (it logs when it does) and exits.
  Calls run one at a time, in order, so generators, closures holding state and the global
  ``random``/NumPy generators behave as in the calling thread.
- inline: each call runs in the calling thread; the deadline is checked after it returns, so a
  call that blocks holds the solve until it returns (then the solve ends with a timeout, and a
  warning says how far the call overran).

Either way, a call that ends past the deadline ends the solve (:class:`CallTimeout`), and the
overrun is kept for the solution's diagnosis.
"""

from __future__ import annotations

import math
import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NoReturn, TypeVar

from sdar_tamp.logs import get_logger

LOG = get_logger(__name__)
T = TypeVar("T")
#: [s] a call may end this long after the deadline without being reported as an overrun
#: (threaded mode waits this much longer before it abandons a call).
OVERRUN_TOLERANCE = 0.1


@dataclass(frozen=True)
class Overrun:
    """A user call that ran past the deadline."""

    what: str  # e.g. "stream 'sample-pose' on inputs ('a',)"
    started: float  # [s] before the deadline the call began (negative: after it)
    overrun: float  # [s] past the deadline: when it returned, or when it was abandoned
    abandoned: bool  # still running when the solve gave up on it

    def describe(self) -> str:
        if self.abandoned:
            return (
                f"{self.what} was still running {self.overrun:.3g} s past the time limit "
                "and was abandoned (it may still be running in a background thread)"
            )
        return f"{self.what} returned {self.overrun:.3g} s past the time limit"


class CallTimeout(Exception):
    """The deadline passed during or right after a user call (control flow, not an error)."""

    def __init__(self, overrun: Overrun | None) -> None:
        super().__init__(overrun.describe() if overrun is not None else "time limit reached")
        self.overrun = overrun


class _Worker:
    """A daemon thread running one call at a time; the caller waits for each reply."""

    def __init__(self) -> None:
        self.requests: queue.SimpleQueue[Callable[[], Any] | None] = queue.SimpleQueue()
        # (True, value) or (False, exception) per call
        self.replies: queue.SimpleQueue[tuple[bool, Any]] = queue.SimpleQueue()
        self.abandoned: str | None = None  # set to the call's description when abandoned
        self.thread = threading.Thread(target=self._loop, name="stream-call", daemon=True)
        self.thread.start()

    def _loop(self) -> None:
        while True:
            fn = self.requests.get()
            if fn is None:
                return
            start = time.perf_counter()
            try:
                self.replies.put((True, fn()))
            except BaseException as error:  # handed to the caller, who re-raises it
                self.replies.put((False, error))
            if self.abandoned is not None:
                LOG.warning(
                    "abandoned call of %s returned after %.3g s",
                    self.abandoned,
                    time.perf_counter() - start,
                )
                return  # the solve that abandoned it has ended; so does this thread

    def stop(self, wait: float = 0.0) -> None:
        """Ask the thread to exit after its current call; wait for that at most ``wait`` [s]."""
        self.requests.put(None)
        if wait > 0:
            self.thread.join(wait)


class CallRunner:
    """Runs the user calls of one solve against a deadline (``time.perf_counter()`` [s]).

    ``threaded`` only matters for a finite deadline (without one nothing needs stopping, and
    calls run inline). Call :meth:`close` when the solve ends.
    """

    def __init__(self, deadline: float = math.inf, threaded: bool = True) -> None:
        self.deadline = deadline
        self.threaded = threaded and math.isfinite(deadline)
        self.overruns: list[Overrun] = []
        self._worker: _Worker | None = None

    def check(self) -> None:
        """Raise :class:`CallTimeout` when the deadline has passed (before making a call)."""
        if time.perf_counter() >= self.deadline:
            raise CallTimeout(None)

    def call(self, fn: Callable[[], T], what: Callable[[], str]) -> T:
        """``fn()``; raises :class:`CallTimeout` when the call ends past the deadline or is
        abandoned; re-raises what ``fn`` raised. ``what()`` describes the call (only asked for
        when it overruns)."""
        start = time.perf_counter()
        value = self._call_threaded(fn, what, start) if self.threaded else fn()
        end = time.perf_counter()
        if end >= self.deadline:
            self._overrun(what, start, end, abandoned=False)
        return value

    def _call_threaded(self, fn: Callable[[], T], what: Callable[[], str], start: float) -> T:
        worker = self._worker
        if worker is None:
            worker = self._worker = _Worker()
        worker.requests.put(fn)
        try:
            ok, value = worker.replies.get(
                timeout=max(0.0, self.deadline + OVERRUN_TOLERANCE - start)
            )
        except queue.Empty:
            worker.abandoned = what()  # the worker exits once the call returns
            self._worker = None
            try:
                ok, value = worker.replies.get_nowait()  # it may have returned just now
            except queue.Empty:
                self._overrun(lambda: str(worker.abandoned), start, time.perf_counter(), True)
            worker.stop()  # in case it checked the flag before it was set
        if not ok:
            raise value
        result: T = value
        return result

    def _overrun(
        self, what: Callable[[], str], start: float, end: float, abandoned: bool
    ) -> NoReturn:
        overrun = Overrun(what(), self.deadline - start, end - self.deadline, abandoned)
        if abandoned or overrun.overrun > OVERRUN_TOLERANCE:
            self.overruns.append(overrun)
            LOG.warning(
                "%s (the call began %.3g s before the time limit)",
                overrun.describe(),
                overrun.started,
            )
        raise CallTimeout(overrun)

    def close(self) -> None:
        """Stop the worker thread: at once when idle; else (the solve was interrupted during
        a call) after that call. An abandoned worker stops by itself after its call."""
        if self._worker is not None:
            self._worker.stop(wait=1.0)
            self._worker = None
