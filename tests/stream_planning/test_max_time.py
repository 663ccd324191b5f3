"""``max_time`` against user code that blocks, and how user calls are run.

By default (``enforce_max_time=True``) user calls run in a worker thread and one still running
at the time limit is abandoned: the solve returns TIMEOUT, a warning and the diagnosis name the
stream. With ``enforce_max_time=False`` calls run in the calling thread and the deadline is
checked after each. The bounds on elapsed time below are loose on purpose (a sampler blocks
for 30 s; the solve must end well before that).
"""

from __future__ import annotations

import logging
import random
import threading
import time
from collections.abc import Iterator
from typing import Any

import pytest
from test_features import counting, line_problem
from test_negate import NEGATE, shelf

from sdar_tamp.language.generators import from_gen_fn, from_test
from solvers.solution import Status
from solvers.solve import solve
from solvers.stream_planning.calls import CallRunner, CallTimeout
from solvers.stream_planning.externals import StreamError

ALGORITHMS = ("incremental", "focused", "binding", "adaptive")
BLOCK = 30.0  # [s] how long a blocking sampler blocks (unless released)
CALLS_LOGGER = "sdar_tamp.solvers.stream_planning.calls"


@pytest.fixture
def release() -> Iterator[threading.Event]:
    """An event blocking samplers wait on; set at teardown so abandoned calls end."""
    event = threading.Event()
    yield event
    event.set()
    for thread in threading.enumerate():
        if thread.name == "stream-call":
            thread.join(5.0)


def _call_threads() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name == "stream-call" and t.is_alive()]


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_blocking_sampler_is_abandoned_at_max_time(
    algorithm: str, release: threading.Event, caplog: pytest.LogCaptureFixture
) -> None:
    calls: list[str] = []
    returned: list[bool] = []

    def blocking(b: str, r: str) -> Iterator[tuple[float]]:
        while True:
            calls.append(threading.current_thread().name)
            release.wait(BLOCK)
            returned.append(True)
            yield (5.0,)

    with caplog.at_level(logging.WARNING, logger=CALLS_LOGGER):
        solution = solve(
            line_problem(from_gen_fn(blocking)), algorithm=algorithm, max_time=1, verbose=False
        )
    assert not returned  # solve came back while the call was still blocked: it was abandoned
    assert solution.status is Status.TIMEOUT
    assert calls == ["stream-call"]  # one call, made in the worker thread
    assert any("'sample-pose'" in r and "abandoned" in r for r in solution.diagnosis)
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert any("'sample-pose'" in m and "abandoned" in m for m in warnings), warnings
    release.set()  # the abandoned call returns; its thread reports it and exits
    for thread in _call_threads():
        thread.join(5.0)
    assert not _call_threads()
    assert any("abandoned call of stream 'sample-pose'" in r.getMessage() for r in caplog.records)


def test_blocking_negated_test_is_abandoned(release: threading.Event) -> None:
    returned: list[bool] = []

    def blocked(x: str) -> bool:
        release.wait(BLOCK)
        returned.append(True)
        return False

    solution = solve(shelf(from_test(blocked)), stream_info=NEGATE, max_time=1, verbose=False)
    assert not returned  # solve came back while the call was still blocked
    assert solution.status is Status.TIMEOUT
    assert any("'test-blocked'" in r and "abandoned" in r for r in solution.diagnosis)


def test_inline_calls_overrun_is_reported_after_the_call(
    caplog: pytest.LogCaptureFixture,
) -> None:
    threads: list[str] = []

    def slow(b: str, r: str) -> Iterator[tuple[float]]:
        while True:
            threads.append(threading.current_thread().name)
            time.sleep(2.0)
            yield (5.0,)

    # a limit long enough for the first call to start on a loaded machine, shorter than the call
    start = time.perf_counter()
    with caplog.at_level(logging.WARNING, logger=CALLS_LOGGER):
        solution = solve(line_problem(from_gen_fn(slow)), max_time=1.5, enforce_max_time=False,
                         verbose=False)  # fmt: skip
    assert time.perf_counter() - start >= 2.0  # the call could not be interrupted
    assert solution.status is Status.TIMEOUT
    assert threads == [threading.current_thread().name]  # called in this thread, once
    assert any("'sample-pose'" in r and "returned" in r for r in solution.diagnosis)
    assert any("'sample-pose'" in r.getMessage() for r in caplog.records)


@pytest.mark.parametrize("enforce", [True, False])
def test_call_modes_give_the_same_plan(enforce: bool) -> None:
    def poses(b: str, r: str) -> Iterator[tuple[float]]:
        while True:
            yield (round(5.0 + random.random(), 6),)

    solution = solve(line_problem(from_gen_fn(poses)), max_time=30, seed=3,
                     enforce_max_time=enforce, verbose=False)  # fmt: skip
    assert solution.solved
    random.seed(3)
    assert [a.args for a in solution.plan or []] == [("a", 0.0, round(5.0 + random.random(), 6))]
    assert not _call_threads()  # the worker stops with the solve


def test_sampler_error_in_worker_is_a_stream_error() -> None:
    def broken(b: str, r: str) -> Iterator[tuple[float]]:
        raise KeyError("oops")
        yield (0.0,)

    with pytest.raises(StreamError, match=r"sample-pose.*KeyError") as info:
        solve(line_problem(from_gen_fn(broken)), max_time=30, verbose=False)
    assert isinstance(info.value.__cause__, KeyError)
    assert not _call_threads()


def test_without_max_time_calls_run_inline() -> None:
    threads: list[str] = []

    def poses(b: str, r: str) -> Iterator[tuple[float]]:
        threads.append(threading.current_thread().name)
        yield from counting()(b, r)

    assert solve(line_problem(from_gen_fn(poses)), verbose=False).solved
    assert threads == [threading.current_thread().name]


# --- the runner on its own ---------------------------------------------------------------


def _describe() -> str:
    return "call 'x'"


@pytest.mark.parametrize("threaded", [True, False])
def test_runner_returns_values_and_reraises(threaded: bool) -> None:
    runner = CallRunner(time.perf_counter() + 60, threaded)
    assert runner.call(lambda: 41 + 1, _describe) == 42

    def fail() -> Any:
        raise StopIteration

    with pytest.raises(StopIteration):
        runner.call(fail, _describe)
    assert runner.overruns == []
    runner.close()


def test_runner_refuses_calls_after_the_deadline() -> None:
    runner = CallRunner(time.perf_counter() - 1.0)
    with pytest.raises(CallTimeout):
        runner.check()
    assert runner.overruns == []  # nothing ran late


def test_runner_inline_overrun_names_the_call() -> None:
    runner = CallRunner(time.perf_counter() + 0.05, threaded=False)
    with pytest.raises(CallTimeout) as info:
        runner.call(lambda: time.sleep(0.5), _describe)
    assert info.value.overrun is not None and not info.value.overrun.abandoned
    assert [o.what for o in runner.overruns] == ["call 'x'"]
    assert runner.overruns[0].overrun > 0.1


def test_runner_threaded_abandons_a_blocked_call(release: threading.Event) -> None:
    runner = CallRunner(time.perf_counter() + 0.2, threaded=True)
    returned: list[bool] = []

    def blocked() -> None:
        release.wait(BLOCK)
        returned.append(True)

    with pytest.raises(CallTimeout) as info:
        runner.call(blocked, _describe)
    assert not returned  # the runner gave up while the call was still blocked
    assert info.value.overrun is not None and info.value.overrun.abandoned
    assert "call 'x'" in str(info.value)
    runner.close()
