"""``sdar bench`` under SIGINT, SIGTERM and SIGKILL: a one-line message, the finished rows
kept, and no worker process left behind. Runs the command in a subprocess (Linux: /proc)."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from sdar_tamp.evaluation.results import RESULTS, load_results

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc")


def _stat(pid: int) -> tuple[str, int] | None:
    """(state, parent pid) of a process, ``None`` once it is gone."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2 :].split()
    return fields[0], int(fields[1])


def _alive(pid: int) -> bool:
    stat = _stat(pid)
    return stat is not None and stat[0] not in "ZX"


def _descendants(pid: int) -> set[int]:
    parents: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit() and (stat := _stat(int(entry.name))) is not None:
            parents[int(entry.name)] = stat[1]
    found, frontier = set(), {pid}
    while frontier:
        frontier = {p for p, parent in parents.items() if parent in frontier} - found
        found |= frontier
    return {p for p in found if _alive(p)}


def _until(condition: Callable[[], bool], timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.1)


def _start(tmp_path: Path, only: str) -> tuple[subprocess.Popen[bytes], Path]:
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "sdar_tamp.cli", "bench", "--out", str(out), "--only", only,
           "--combos", "all", "--workers", "1", "--time-limit", "20", "-q"]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    with (tmp_path / "stdout").open("wb") as so, (tmp_path / "stderr").open("wb") as se:
        proc = subprocess.Popen(cmd, stdout=so, stderr=se, env=env, cwd=tmp_path,
                                start_new_session=True)  # fmt: skip
    return proc, out


def _rows(out: Path) -> int:
    return len(load_results(out)) if (out / RESULTS).exists() else 0


def _stop(proc: subprocess.Popen[bytes]) -> None:
    """Kill whatever is left of the command's process group (the test's own clean-up)."""
    with contextlib.suppress(ProcessLookupError):
        os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()


def test_ctrl_c_keeps_rows_and_prints_one_line(tmp_path: Path) -> None:
    proc, out = _start(tmp_path, "R4,S4,D4")  # 18 runs: far from finished at the first row
    try:
        _until(lambda: _rows(out) >= 1 or proc.poll() is not None, 300, "a first row")
        workers = _descendants(proc.pid)
        before = (out / RESULTS).read_text()
        os.killpg(proc.pid, signal.SIGINT)  # what Ctrl-C in a terminal does: the whole group
        assert proc.wait(timeout=60) == 130
    finally:
        _stop(proc)
    err = (tmp_path / "stderr").read_text()
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    lines = err.strip().splitlines()
    assert lines[-1].startswith("sdar bench: interrupted (SIGINT);"), err
    assert "resume" in lines[-1] and str(out / RESULTS) in lines[-1]
    text = (out / RESULTS).read_text()
    assert text.startswith(before) and text.endswith("\n")
    assert len(load_results(out)) == text.count("\n") - 1 < 18  # complete rows only
    _until(lambda: not any(_alive(p) for p in workers), 20, "the workers to end")


def test_sigterm_ends_the_workers(tmp_path: Path) -> None:
    proc, _ = _start(tmp_path, "R4,S4")
    try:
        _until(lambda: bool(_descendants(proc.pid)), 120, "a worker process")
        workers = _descendants(proc.pid)
        os.kill(proc.pid, signal.SIGTERM)  # the parent alone
        assert proc.wait(timeout=60) == 128 + signal.SIGTERM
    finally:
        _stop(proc)
    err = (tmp_path / "stderr").read_text()
    assert "Traceback" not in err, err
    assert err.strip().splitlines()[-1].startswith("sdar bench: interrupted (SIGTERM);"), err
    _until(lambda: not any(_alive(p) for p in workers), 20, "the workers to end")


def test_sigkill_of_the_parent_leaves_no_worker(tmp_path: Path) -> None:
    proc, out = _start(tmp_path, "R4,S4")
    try:
        _until(lambda: _rows(out) >= 1 or proc.poll() is not None, 300, "a first row")
        workers = _descendants(proc.pid)  # the worker is now busy with the next run
        assert workers and proc.poll() is None
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=60)
        _until(lambda: not any(_alive(p) for p in workers), 20, "the orphaned workers to end")
    finally:
        _stop(proc)
    assert len(load_results(out)) >= 1
