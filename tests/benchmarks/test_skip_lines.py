"""The skip lines of the benchmarks that need what the repository does not hold: in
``--quick``, without it, the last line is ``{"skipped": "<why>", ...}`` and the run ends
normally; a full run without it is refused instead where it cannot do anything useful."""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import pytest

Loader = Callable[[str], ModuleType]


def _last_line(capsys: pytest.CaptureFixture[str]) -> dict[str, object]:
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert isinstance(out, dict)
    return out


def test_pddlstream_examples_without_a_checkout(
    benchmark_script: Loader,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    tmp_path: Path,
) -> None:
    bench = benchmark_script("bench_pddlstream_compat")
    monkeypatch.delenv("PDDLSTREAM_PATH", raising=False)
    for argv, quick in (([], False), (["--quick"], True), ([str(tmp_path), "--quick"], True)):
        assert bench.main(argv) == 0
        out = _last_line(capsys)
        assert out["quick"] is quick
        assert isinstance(out["skipped"], str) and "no PDDLStream checkout" in out["skipped"]


def test_pddlstream_robot_example_without_its_simulator(
    benchmark_script: Loader, tmp_path: Path
) -> None:
    bench = benchmark_script("bench_pddlstream_compat")
    example = bench.Example("kuka", "examples.pybullet.kuka.run", needs="no_such_module_xyz")
    row = bench.run_example(tmp_path, example, 1.0)
    assert row["skipped"] is True and row["passed"] is False and row["seconds"] == 0.0
    assert "needs 'no_such_module_xyz'" in str(row["result"])
    assert {e.name for e in bench.EXAMPLES if e.needs == "pybullet"} == {
        "kuka",
        "pr2",
        "namo",
        "pr2_rovers",
        "pr2_belief",
        "tamp",
        "turtlebot_rovers",
        "turtlebots",
    }


def test_pddlstream_examples_run_within_their_own_time_limits(benchmark_script: Loader) -> None:
    bench = benchmark_script("bench_pddlstream_compat")
    by_name = {e.name: e for e in bench.EXAMPLES}
    allowed = {name: bench.allowed_seconds(e, None, 600.0) for name, e in by_name.items()}
    assert allowed["namo"] == 120.0 + bench.SETUP_SECONDS  # its own max_time, plus loading
    assert allowed["turtlebots"] == 300.0 + bench.SETUP_SECONDS
    assert allowed["kuka"] == allowed["pr2_belief"] == 600.0  # no limit of its own
    assert allowed["blocksworld"] == bench.DEFAULT_TIMEOUT  # states none
    assert all(bench.allowed_seconds(e, 5.0, 600.0) == 5.0 for e in bench.EXAMPLES)
    assert "turtlebots" in {e.name for e in bench.EXAMPLES if e.upstream}


def test_classical_without_its_problem_folder(
    benchmark_script: Loader, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    bench = benchmark_script("bench_classical")
    missing = tmp_path / "ipc"
    summary = bench.main(["--quick", "--suite", str(missing)])
    assert _last_line(capsys) == summary
    assert summary["quick"] is True and str(missing) in summary["skipped"]
    with pytest.raises(SystemExit) as info:  # a full run is refused
        bench.main(["--suite", str(missing)])
    assert info.value.code == 2
    assert f"--suite: {missing} is not a folder" in capsys.readouterr().err


def test_hard_motion_set_without_ompl(
    benchmark_script: Loader, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    bench = benchmark_script("bench_motion")
    monkeypatch.setitem(sys.modules, "ompl", None)  # importlib finds no such module
    bench.main(["--quick", "--hard", "1"])
    out = _last_line(capsys)
    assert out["quick"] is True and "OMPL is not installed" in str(out["skipped"])


def test_stream_benchmark_without_a_pddlstream_checkout(
    benchmark_script: Loader, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """The continuous_tamp rows are skipped, and the summary says why; the rest runs."""
    bench = benchmark_script("bench_streams")
    argv = ["--quick", "--domains", "infeasible", "--algorithms", "adaptive"]
    argv += ["--kitchen-seeds", "0", "--limit-probe", "0", "--pddlstream", str(tmp_path)]
    assert bench.main(argv) == 0
    out = _last_line(capsys)
    assert out["continuous_tamp"] == [] and out["continuous_tamp_runs"] == 0
    assert "no PDDLStream checkout" in str(out["continuous_tamp_skipped"])
    assert out["runs"] and out["all_expected"] is True


def test_a_seeded_example_draws_the_same_numbers(benchmark_script: Loader, tmp_path: Path) -> None:
    """``run_example(..., seed=S)`` seeds Python's and NumPy's generators before the program:
    two runs of an unseeded program draw the same numbers, another seed others."""
    bench = benchmark_script("bench_pddlstream_compat")
    checkout = tmp_path / "checkout"
    (checkout / "examples").mkdir(parents=True)
    (checkout / "examples" / "__init__.py").write_text("")
    out = tmp_path / "drawn.txt"
    (checkout / "examples" / "draw.py").write_text(
        "import random, numpy\n"
        f"with open({str(out)!r}, 'a') as f:\n"
        "    f.write(f'{random.random()} {numpy.random.rand()}\\n')\n"
    )
    example = bench.Example("draw", "examples.draw")
    for seed in (3, 3, 4):
        row = bench.run_example(checkout, example, 60.0, seed=seed)
        assert row["result"] == "no plan" and row["solve_seconds"] == 0.0
    first, again, other = out.read_text().splitlines()
    assert first == again and first != other
