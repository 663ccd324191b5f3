"""The ``ray`` backend on a local Ray: a tiny sweep, instances carried as text, the hard limit
(the task's process is killed, a ``timeout`` row written), and a cluster that is not there.
Skipped without Ray (``pip install 'sdar-tamp[cluster]'``)."""

from __future__ import annotations

import json
import os
import signal
import socket
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from types import FrameType
from typing import Any

import pytest

from sdar_tamp.cli import main
from sdar_tamp.errors import ParameterError
from sdar_tamp.evaluation.backends import BackendError
from sdar_tamp.evaluation.bench_task import BenchTask, run_task
from sdar_tamp.evaluation.payload import pack
from sdar_tamp.evaluation.ray_backend import RayBackend, probe
from sdar_tamp.evaluation.results import COMBINATIONS, RESULTS, load_results, plan_path
from sdar_tamp.evaluation.runner import run_bench
from sdar_tamp.evaluation.settings import SETTINGS
from sdar_tamp.evaluation.suite import SuiteEntry, suite_entries
from sdar_tamp.evaluation.workers import WorkerFailure
from sdar_tamp.plan_reading import load_plan

ray: Any = pytest.importorskip("ray")

SDAR = next(c for c in COMBINATIONS if c.id == "sdar")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
    return port  # closed again: nothing listens there


def _on_sigterm(signum: int, frame: FrameType | None) -> None:
    raise AssertionError("not to be called")


def test_tiny_sweep_on_a_local_ray(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """R4 with SDAR in one Ray task on a Ray started for the sweep; a rerun resumes."""
    assert not ray.is_initialized()
    previous = signal.signal(signal.SIGTERM, _on_sigterm)
    try:
        run_bench("paper", tmp_path, "sdar", instances=["R4"], time_limit=30.0, workers=1,
                  backend="ray", progress=False)  # fmt: skip
        assert signal.getsignal(signal.SIGTERM) is _on_sigterm  # Ray's handler not left behind
    finally:
        signal.signal(signal.SIGTERM, previous)
    assert not ray.is_initialized()  # the Ray it started is shut down
    (row,) = load_results(tmp_path)
    assert (row["instance"], row["combination"], row["status"]) == ("R4", "sdar", "solved")
    assert row["success"] == "1" and row["abstract_actions"] == "4"
    plan = load_plan(plan_path(tmp_path, "R4", "sdar"))  # kept by the driver
    assert plan.instance == "R4" and len(plan.steps) == int(row["steps"])
    record = json.loads((tmp_path / SETTINGS).read_text())
    assert record["backend"] == "ray" and record["workers"] == 1 and record["shard"] == ""
    before = (tmp_path / RESULTS).read_text()
    args = ["bench", "--out", str(tmp_path), "--only", "R4", "--combos", "sdar",
            "--time-limit", "30", "--workers", "1", "--backend", "ray", "-q"]  # fmt: skip
    assert main(args) == 0  # resumes: nothing left, so no Ray is started
    assert (tmp_path / RESULTS).read_text() == before and not ray.is_initialized()
    assert (
        "--workers 1 --time-limit 30 --seed 0 --backend ray" in (tmp_path / "report.md").read_text()
    )
    assert main([*args[:-3], "-q"]) == 2  # the process backend: other settings
    assert "backend process (the rows: ray)" in capsys.readouterr().err


def test_unreachable_cluster_is_a_quick_clear_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Nothing listens at the address: refused at once (Ray itself would retry for minutes)."""
    address = f"127.0.0.1:{_free_port()}"
    out = tmp_path / "out"
    with pytest.raises(BackendError, match=f"cannot reach the Ray cluster at {address}"):
        run_bench("paper", out, "sdar", instances=["R4"], backend="ray", address=address)
    monkeypatch.setenv("RAY_ADDRESS", address)  # the same through the environment
    assert main(["bench", "--out", str(out), "--only", "R4", "--backend", "ray", "-q"]) == 2
    assert f"cannot reach the Ray cluster at {address}" in capsys.readouterr().err
    assert not out.exists() and not ray.is_initialized()
    with pytest.raises(ParameterError, match="address must be host:port"):
        probe("headnode")
    with pytest.raises(BackendError, match="cannot reach"):
        probe("192.0.2.1:6379", timeout=0.2)  # TEST-NET-1: never answers


@pytest.fixture(scope="module")
def local_ray() -> Iterator[None]:
    ray.init(address="local", num_cpus=1, include_dashboard=False, configure_logging=False,
             log_to_driver=False)  # fmt: skip
    # the tests' own helpers travel by value: the workers cannot import this test module
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])
    yield
    ray.shutdown()


def test_tasks_carry_the_instance_text(local_ray: None) -> None:
    """The task names a file that does not exist: the worker solves from the carried text."""
    real = suite_entries("paper", only=["R4"])[0].path
    entry = SuiteEntry(Path("/nonexistent/R4.yaml"), "R4", "R", 4)
    task = BenchTask(entry, SDAR, time_limit=30.0, seed=0, files=pack(real))
    with RayBackend(run_task, workers=1, hard_limit=300.0) as backend:
        ((done, answer),) = list(backend.run([task]))
    assert done is task and not isinstance(answer, WorkerFailure), answer
    row, steps, plan = answer.row, answer.step_times, answer.plan
    assert row.status == "solved" and row.abstract_actions == 4
    assert plan is not None and plan.instance == "R4" and len(steps) == row.steps


def _stuck(pid_file: str) -> None:
    Path(pid_file).write_text(str(os.getpid()))
    time.sleep(120)


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state not in "ZX"


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc")
def test_overrunning_task_is_killed(tmp_path: Path, local_ray: None) -> None:
    pid_file = tmp_path / "pid"
    with RayBackend(_stuck, workers=1, hard_limit=1.0, poll=0.1) as backend:
        ((_, answer),) = list(backend.run([str(pid_file)]))
    assert isinstance(answer, WorkerFailure) and answer.timed_out and not answer.external
    assert "hard limit of 1 s: Ray task killed" in answer.reason
    pid = int(pid_file.read_text())
    deadline = time.monotonic() + 30
    while _alive(pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not _alive(pid)


def test_overrun_is_recorded_as_timeout_row(tmp_path: Path, local_ray: None) -> None:
    # N24 plans for tens of seconds: far beyond the 1 s limit on any machine
    run_bench("dense", tmp_path, "sdar", instances=["N24"], backend="ray", hard_limit=1.0,
              progress=False)  # fmt: skip
    (row,) = load_results(tmp_path)
    assert row["status"] == "timeout" and row["success"] == "0"
    assert "hard limit of 1 s: Ray task killed" in row["diagnosis"]
    assert not plan_path(tmp_path, "N24", "sdar").exists()
    assert ray.is_initialized()  # a Ray the caller started stays up


def test_a_node_without_the_code_stops_the_sweep(
    tmp_path: Path, local_ray: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The task's function cannot be unpacked on the node: one clear error, not error rows."""
    (tmp_path / "only_on_the_driver.py").write_text("def run(task):\n    return task\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    import only_on_the_driver  # type: ignore[import-not-found]

    missing = r"\(ModuleNotFoundError: No module named 'only_on_the_driver'\)"
    backend = RayBackend(only_on_the_driver.run, workers=1, hard_limit=60.0)
    expected = f"could not start on its node {missing}; every node"
    with pytest.raises(BackendError, match=expected), backend:
        list(backend.run([1, 2]))


def test_a_task_that_never_starts_is_not_recorded(
    tmp_path: Path, local_ray: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    """One CPU, two tasks at once: the second waits in Ray's queue past the limit, so it is
    cancelled as not started (``external``: a rerun runs it), not as a timeout."""
    import sdar_tamp.evaluation.ray_backend as ray_backend

    monkeypatch.setattr(ray_backend, "STARTUP_LIMIT", 0.5)
    files = [str(tmp_path / "first"), str(tmp_path / "second")]
    with RayBackend(_stuck, workers=2, hard_limit=5.0, poll=0.1) as backend:  # 5 s to start
        answers = dict(backend.run(files))
    failures = [a for a in answers.values() if isinstance(a, WorkerFailure)]
    assert len(failures) == 2
    started = [a for a in failures if a.timed_out]
    queued = [a for a in failures if a.external]
    assert len(started) == 1 and not started[0].external
    assert len(queued) == 1 and "did not start within 5 s" in queued[0].reason
