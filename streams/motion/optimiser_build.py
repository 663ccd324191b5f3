"""A trajectory optimiser built in a background thread, so that constructing a planner costs
nothing and only the first optimisation may wait for the build."""

from __future__ import annotations

import threading
import time

from sdar_tamp.logs import get_logger
from streams.context import WorldContext
from streams.motion.optimiser import TrajectoryOptimiser
from streams.motion.optimiser_records import TrajOptOptions

_log = get_logger(__name__)


class OptimiserBuild:
    """A :class:`TrajectoryOptimiser` under construction in a background thread (building the NLP
    takes a few tenths of a second of CPU; planning that needs no optimisation goes on meanwhile).

    :meth:`get` waits for it (``waited`` [s] adds up the waits) and re-raises an error of
    the build. ``build_time`` [s] is the CPU time of the build (NaN until it is done).

    ``start=False`` defers the background build to :meth:`start` (or to the first
    :meth:`get`): a caller whose first planning needs no optimiser keeps the build's CPU
    time (and its hold on the interpreter) out of it."""

    def __init__(
        self,
        ctx: WorldContext,
        options: TrajOptOptions,
        background: bool = True,
        start: bool = True,
    ) -> None:
        self.options = options
        self.build_time = float("nan")
        self.waited = 0.0
        self._result: TrajectoryOptimiser | None = None
        self._error: BaseException | None = None
        self._done = threading.Event()
        self._ctx: WorldContext | None = ctx
        self._lock = threading.Lock()
        if not background:
            self._ctx = None
            self._run(ctx)
        elif start:
            self.start()

    @property
    def started(self) -> bool:
        """The build has started (or is done)."""
        return self._ctx is None

    def start(self) -> None:
        """Start the background build, unless it has started already."""
        with self._lock:
            ctx, self._ctx = self._ctx, None
        if ctx is None:
            return
        # Not a daemon: the interpreter waits for a build in progress before it shuts down
        # (CasADi code still running during finalisation crashes the process).
        name = "sdar-trajopt-build"
        threading.Thread(target=self._run, args=(ctx,), name=name, daemon=False).start()

    def _run(self, ctx: WorldContext) -> None:
        start = time.thread_time()
        try:
            self._result = TrajectoryOptimiser(ctx, self.options)
        except BaseException as error:  # handed to the caller of get()
            self._error = error
        finally:
            self.build_time = time.thread_time() - start
            self._done.set()
        if self._result is not None and self.options.compiled:
            # after the optimiser is handed out: the code generation (about 0.5 s) delays
            # no solve; the solver switches to the compiled derivatives once they exist
            self._request_compiled(self._result)

    @staticmethod
    def _request_compiled(optimiser: TrajectoryOptimiser) -> None:
        """Compiled derivatives are a speed-up only: whatever stops them, the build stands."""
        try:
            optimiser.request_compiled()
        except Exception as error:  # any failure leaves CasADi's own evaluation
            _log.info("compiled derivatives unavailable, kept uncompiled: %s", error)

    @property
    def ready(self) -> bool:
        return self._done.is_set()

    def get(self) -> TrajectoryOptimiser:
        """The optimiser, once built (a deferred build starts now)."""
        self.start()
        if not self._done.is_set():
            start = time.perf_counter()
            _log.info("waiting for the trajectory optimiser to be built")
            self._done.wait()
            self.waited += time.perf_counter() - start
        if self._error is not None:
            raise self._error
        assert self._result is not None
        return self._result
