"""The benchmark's worker processes: answers, failures, the hard limit, death with the parent.

The tasks are standard-library functions (``time.sleep``, ``os._exit``, ``int``) so that the
spawned workers import nothing heavy."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.evaluation import workers
from sdar_tamp.evaluation.workers import WorkerFailure, WorkerPool

ROOT = Path(__file__).resolve().parents[2]


def test_results_and_failures() -> None:
    with WorkerPool(int, workers=2) as pool:
        answers = dict(pool.run(["7", "x", "12"]))
    assert answers["7"] == 7 and answers["12"] == 12
    failure = answers["x"]
    assert isinstance(failure, WorkerFailure) and "ValueError" in failure.reason
    assert not failure.external


def test_a_dead_worker_is_reported_and_replaced() -> None:
    with WorkerPool(os._exit, workers=1) as pool:
        answers = list(pool.run([3, 4]))
    assert [task for task, _ in answers] == [3, 4]
    for code, (_, failure) in zip((3, 4), answers, strict=True):
        assert isinstance(failure, WorkerFailure) and f"exit code {code}" in failure.reason


def test_hard_limit_kills_a_stuck_task() -> None:
    with WorkerPool(time.sleep, workers=1, hard_limit=1.0) as pool:
        answers = list(pool.run([600.0, 0.0]))
        assert len(pool.pids) == 1  # the stuck worker was replaced by a fresh one
    assert answers[0][0] == 600.0 and isinstance(answers[0][1], WorkerFailure)
    assert "hard limit of 1 s" in answers[0][1].reason
    assert answers[1] == (0.0, None)


def test_externally_terminated_worker_is_flagged() -> None:
    with WorkerPool(time.sleep, workers=1) as pool:

        def terminate() -> None:
            deadline = time.monotonic() + 60
            while not pool.pids and time.monotonic() < deadline:
                time.sleep(0.05)
            time.sleep(0.5)
            os.kill(pool.pids[0], signal.SIGTERM)

        threading.Thread(target=terminate, daemon=True).start()
        [(task, failure)] = list(pool.run([600.0]))
    assert task == 600.0 and isinstance(failure, WorkerFailure)
    assert failure.external and "SIGTERM" in failure.reason


@pytest.mark.skipif(not hasattr(signal, "pthread_sigmask"), reason="needs pthread_sigmask")
def test_a_signal_during_start_up_is_handled_once_the_worker_is_listed(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Another thread that blocks nothing takes a signal sent to the process (as BLAS
    # threads do); the handler must still not run while a worker is half started.
    idle = threading.Event()
    threading.Thread(target=idle.wait, daemon=True).start()
    real_block = workers._block

    def block_then_signal(signals: set[int], how: str = "block") -> set[int]:
        previous = real_block(signals, how)
        if how == "block":
            os.kill(os.getpid(), signal.SIGTERM)  # arrives on the idle thread
            time.sleep(0.2)
        return previous

    monkeypatch.setattr(workers, "_block", block_then_signal)
    pool: WorkerPool[int, int] = WorkerPool(int, workers=1)
    listed: list[int] = []

    class Stopped(Exception):
        pass

    def handler(signum: int, frame: object) -> None:
        listed.append(len(pool.pids))
        raise Stopped

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        with pytest.raises(Stopped):
            pool._start()
    finally:
        signal.signal(signal.SIGTERM, previous)
        idle.set()
        live = [w.process for w in pool._live]
        pool.close(kill=True)
    assert listed == [1]  # handled once, with the new worker on the list close() kills
    assert len(live) == 1 and live[0].exitcode == -signal.SIGKILL


def test_bad_arguments() -> None:
    with pytest.raises(ParameterError, match="workers must be >= 1"):
        WorkerPool(int, workers=0)
    with pytest.raises(ParameterError, match="hard limit must be > 0"):
        WorkerPool(int, workers=1, hard_limit=0.0)


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc")
def test_busy_worker_dies_with_its_parent(tmp_path: Path) -> None:
    script = (
        "import sys, time\n"
        "from sdar_tamp.evaluation.workers import WorkerPool\n"
        "with WorkerPool(time.sleep, workers=1) as pool:\n"
        "    results = pool.run([600.0])\n"
        "    import threading\n"
        "    def report():\n"
        "        while not pool.pids: time.sleep(0.05)\n"
        "        print(pool.pids[0], flush=True)\n"
        "    threading.Thread(target=report, daemon=True).start()\n"
        "    list(results)\n"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, env=env, cwd=tmp_path,
        start_new_session=True,
    )  # fmt: skip
    try:
        assert proc.stdout is not None
        worker = int(proc.stdout.readline())
        time.sleep(1.0)  # the worker is now inside time.sleep(600)
        assert _alive(worker)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=60)
        deadline = time.monotonic() + 20
        while _alive(worker) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not _alive(worker)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()


def _alive(pid: int) -> bool:
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return text[text.rindex(")") + 2] not in "ZX"
