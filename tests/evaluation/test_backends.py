"""Choosing a backend: bad choices refused before anything is written; a run that overruns
the hard limit recorded as a timeout (process backend; the Ray one: test_ray_backend.py)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from sdar_tamp.cli import main
from sdar_tamp.errors import ParameterError
from sdar_tamp.evaluation.backends import BackendError, check_backend
from sdar_tamp.evaluation.results import load_results, load_steps, plan_path
from sdar_tamp.evaluation.runner import run_bench


def test_unknown_backend(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    with pytest.raises(ParameterError, match="backend must be one of process, ray; got 'dask'"):
        run_bench("paper", out, "sdar", instances=["R4"], backend="dask", progress=False)
    with pytest.raises(SystemExit) as stop:
        main(["bench", "--out", str(out), "--backend", "dask"])
    assert stop.value.code == 2 and "invalid choice: 'dask'" in capsys.readouterr().err
    assert not out.exists()


def test_address_is_for_ray_only(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(ParameterError, match="address is for the ray backend only"):
        check_backend("process", "10.0.0.1:6379")
    out = tmp_path / "out"
    assert main(["bench", "-o", str(out), "--only", "R4", "--address", "h:1", "-q"]) == 2
    assert "address is for the ray backend only" in capsys.readouterr().err
    assert not out.exists()


def test_ray_backend_without_ray(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # what an installation without Ray sees
    out = tmp_path / "out"
    with pytest.raises(BackendError, match=r"pip install 'sdar-tamp\[cluster\]'"):
        run_bench("paper", out, "sdar", instances=["R4"], backend="ray", progress=False)
    assert not out.exists()


def test_overrun_is_killed_and_recorded_as_timeout(tmp_path: Path) -> None:
    """A hard limit of 1 s: the worker is killed in the middle of set-up and solve. N24 (24
    objects) takes tens of seconds to plan, far beyond 1 s on any machine; R4 did not (a fast
    machine solved it inside the limit)."""
    run_bench("dense", tmp_path, "sdar", instances=["N24"], hard_limit=1.0, progress=False)
    (row,) = load_results(tmp_path)
    assert row["status"] == "timeout" and row["success"] == "0"
    assert "hard limit of 1 s: worker killed" in row["diagnosis"]
    assert not load_steps(tmp_path) and not plan_path(tmp_path, "N24", "sdar").exists()
