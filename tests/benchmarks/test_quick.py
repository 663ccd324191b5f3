"""Every benchmark's ``--quick`` run, so that no benchmark stops working unseen.

Each ``benchmarks/bench_*.py`` (found by glob: a new benchmark without ``--quick`` fails here)
runs as ``python SCRIPT --quick`` in a fresh process from an empty folder, with this checkout
first on its path and its byte code and numba's cache kept out of the checkout. It must exit 0
and end its output with one JSON object holding ``"quick": true`` and the figures checked
below. A benchmark that needs what the repository does not hold (a PDDLStream checkout, OMPL)
may end with ``{"skipped": "<why>", ...}`` instead; the test then skips with that reason.

One test class per benchmark: ``pytest --dist loadscope`` keeps a module's test functions (their
parametrisations included) in one process but gives each class its own share, so the classes
spread the benchmarks over the processes.
"""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPTS = sorted((ROOT / "benchmarks").glob("bench_*.py"))
#: guards against a hung benchmark only (a quick run takes seconds)
HANG_GUARD = 900.0  # [s]

#: Runs besides ``--quick`` alone (their arguments after ``--quick``): other modes kept alive
#: bench_sdar in a cell named on the command line (the shipped one, as a file)
IN_CELL = ("--scene", str(ROOT / "domains/dual_arm_rearrangement/cells/ur5e_facing.yaml"))
#: bench_sdar's bounds alone, on a 24-object instance of the 4-arm table's suite
BOUNDS = ("--bound-only", "--suite", "table_4arm", "--only", "S24-1")
#: bench_sdar with the time limit on this process's CPU seconds
CPU_CLOCK = ("--cpu-clock",)
EXTRA_RUNS: dict[str, tuple[tuple[str, ...], ...]] = {
    "bench_motion": (("--hard", "1"),),
    "bench_sdar": (IN_CELL, BOUNDS, CPU_CLOCK),
}
#: The runs that may skip: what they need is not in the repository
MAY_SKIP = {("bench_pddlstream_compat", ()), ("bench_motion", ("--hard", "1"))}

Summary = dict[str, Any]


def _arm_ik(out: Summary) -> None:
    ur, arm7 = out["arms"]["ur5e"], out["arms"]["panda"]
    assert ur["solver"] == "closed form" and ur["branches"] == 8 and ur["success_rate"] == 1.0
    assert arm7["solver"] == "numeric" and arm7["dof"] == 7 and arm7["poses"] == 100
    assert arm7["success_rate"] >= 0.95 and arm7["max_error"] < 1e-5


def _async(out: Summary) -> None:
    assert out["instances"] == 1 and out["all_valid"] is True
    assert out["median_ratio"] <= 1.0  # the scheduler never returns a longer plan
    assert out["median_ratio_timelines"] <= out["median_ratio"]  # the shorter of the two
    assert out["median_ratio_assigned"] <= out["median_ratio_timelines"]  # the shortest of three
    row = out["rows"][0]
    assert row["assigned_kept"] == (
        row["assigned_found"] is not None and row["assigned"] < row["sync"]
    )


def _cells(out: Summary) -> None:
    assert out["cells"] and all(c["reached_by_all"] == 1.0 for c in out["cells"].values())


def _classical(out: Summary) -> None:
    assert out["problems"] >= 1 and out["solved"]["ours"] == out["problems"]
    assert not any(out["invalid"].values())


def _feasibility(out: Summary) -> None:
    for label in ("paper", "stress", "stress_before"):
        assert out[label]["seconds"], label


def _layout(out: Summary) -> None:
    assert out["benchmark"] == "layout" and out["poses"] == 12 and out["pairs"] > 0
    near, far = out["clearances"]["0.08"], out["clearances"]["0.20"]
    assert far["collide_kept"] <= near["collide_kept"] and far["free_kept"] <= near["free_kept"]


def _motion(out: Summary) -> None:
    assert out["segments"] == 3 and 0.0 <= out["success_rate_with_fallbacks"] <= 1.0
    assert out["validation_failures_returned_as_success"] == 0


def _motion_arms(out: Summary) -> None:
    rows = out["by_arms"]
    assert sorted(rows) == ["1", "2", "3", "4"]
    for k, row in rows.items():
        n = int(k)
        assert row["calls"] == 2 and row["arm_arm_blocks"] == n * (n - 1) // 2
        assert row["exact_check_passed"] <= row["calls"] and row["median_cpu_s"] > 0


def _motion_hard(out: Summary) -> None:
    for kind in ("one_arm", "both_arms"):
        assert {"optimiser", "ompl", "ladder", "sdar-m"} <= out[kind].keys()


def _numeric_ik(out: Summary) -> None:
    ur = out["arms"]["ur5e"]
    assert ur["poses"] == 100 and ur["within_limits"] is True and ur["success_rate"] >= 0.95


def _numeric_ik_planner(out: Summary) -> None:
    planner, default = out["planner"]["planner"], out["planner"]["default"]
    assert out["poses"] == 10 and planner["grasps"] == default["grasps"] == 60
    assert planner["grasps_solved"] >= default["grasps_solved"] > 0
    assert planner["iterations_per_pose"] < default["iterations_per_pose"]
    compiled = out["planner"]["compiled"]  # the same options, descending compiled
    assert compiled["grasps"] == 60 and compiled["grasps_solved"] >= planner["grasps_solved"] - 1
    assert compiled["iterations_per_pose"] is None


def _parser(out: Summary) -> None:
    assert out["init_facts"] > 0 and out["problem_mb_per_s"] > 0


def _pddlstream(out: Summary) -> None:
    assert out["total"] == 1 and "passed" in out


def _replan(out: Summary) -> None:
    assert out["perturbations"] == 3 and out["instances"] == 1
    assert out["valid"] == out["solvable"] >= 1 and out["success_rate"] == 1.0
    assert out["latency_median_s"] > 0 and set(out["by_kind"]) == {"nudge", "remove", "add"}
    assert 0 <= out["compared_fresh_kept"] <= out["compared"] <= out["perturbations"]
    assert out["compare"] == "moving" and 0 <= out["improved"] <= out["perturbations"]
    assert out["latency_median_s"] <= out["latency_final_median_s"] <= out["latency_done_median_s"]


def _sdar(out: Summary) -> None:
    assert out["clock"] == "wall"
    _sdar_plan(out)


def _sdar_cpu(out: Summary) -> None:
    assert out["clock"] == "cpu"
    _sdar_plan(out)


def _sdar_plan(out: Summary) -> None:
    assert out["instances"] == 1 and out["success"] == 1 and out["steps"] > 0
    r4 = out["per_instance"]["R4"]
    assert 0.0 < r4["bound"] < r4["execution_time"] == out["execution_time_median"]
    assert out["execution_over_bound_median"] == r4["execution_over_bound"] > 1.0


def _bounds(out: Summary) -> None:
    assert out["benchmark"] == "sdar-bound" and out["instances"] == 1
    s24 = out["per_instance"]["S24-1"]
    assert s24["arms"] == 4 and s24["bound"] == max(s24["sum_over_arms"], s24["longest_object"])


def _sdar_in_cell(out: Summary) -> None:
    _sdar(out)
    assert out["scene"] == IN_CELL[1]


def _solve(out: Summary) -> None:
    assert out["runs"] == 1 and out["this"]["all_valid"] is True


def _stream(out: Summary) -> None:
    assert out["instances"] == 1 and out["all_same_plan"] is True and out["steps"] >= 1
    assert 0.0 < out["first_step_s"] <= out["stream_total_s"] <= out["stream_done_s"]
    assert out["batch_total_s"] > 0.0


def _spheres(out: Summary) -> None:
    for model in out["models"].values():
        assert model["min_coverage"] >= 0.999 and model["max_volume_ratio"] <= 3.0
    assert {"mesh_arm", "ur5e_all"} <= out["models"].keys()


def _streams(out: Summary) -> None:
    assert out["runs"] and out["all_expected"] is True and out["max_time_probes"]
    assert out["kitchen_2d"]  # per seed: wall and CPU time
    assert all(len(r["times"]) == len(r["cpus"]) == r["seeds"] for r in out["kitchen_2d"])


def _world(out: Summary) -> None:
    keys = ("ik_poses_per_s_per_core", "collision_checks_per_s_12_objects",
            "dependency_graph_24_objects_ms", "exact_fvs_24_object_component_ms")  # fmt: skip
    assert all(out[key] > 0 for key in keys)


#: What a run's summary must show (runs not named here: only the common checks)
CHECKS: dict[tuple[str, tuple[str, ...]], Callable[[Summary], None]] = {
    ("bench_arm_ik", ()): _arm_ik,
    ("bench_async", ()): _async,
    ("bench_cells", ()): _cells,
    ("bench_classical", ()): _classical,
    ("bench_feasibility", ()): _feasibility,
    ("bench_layout", ()): _layout,
    ("bench_motion", ()): _motion,
    ("bench_motion", ("--hard", "1")): _motion_hard,
    ("bench_motion_arms", ()): _motion_arms,
    ("bench_numeric_ik", ()): _numeric_ik,
    ("bench_numeric_ik", ("--planner",)): _numeric_ik_planner,
    ("bench_parser", ()): _parser,
    ("bench_pddlstream_compat", ()): _pddlstream,
    ("bench_replan", ()): _replan,
    ("bench_sdar", ()): _sdar,
    ("bench_sdar", IN_CELL): _sdar_in_cell,
    ("bench_sdar", BOUNDS): _bounds,
    ("bench_sdar", CPU_CLOCK): _sdar_cpu,
    ("bench_solve", ()): _solve,
    ("bench_spheres", ()): _spheres,
    ("bench_stream", ()): _stream,
    ("bench_streams", ()): _streams,
    ("bench_world", ()): _world,
}


def run_quick(script: Path, extra: tuple[str, ...], folder: Path) -> Summary:
    """Run ``script --quick *extra`` from ``folder``; its last output line, read as JSON."""
    env = dict(os.environ)  # tests/conftest.py switched the compiled derivatives off
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    env["NUMBA_CACHE_DIR"] = str(folder / "numba-cache")
    done = subprocess.run(
        [sys.executable, str(script), "--quick", *extra],
        cwd=folder,
        env=env,
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        check=False,
        timeout=HANG_GUARD,
    )
    said = f"stdout ends:\n{done.stdout[-2000:]}\nstderr ends:\n{done.stderr[-2000:]}"
    assert done.returncode == 0, f"{script.name} exited {done.returncode}\n{said}"
    lines = done.stdout.strip().splitlines()
    assert lines, f"{script.name} printed nothing\n{said}"
    out = json.loads(lines[-1])
    assert isinstance(out, dict), f"{script.name}: the last line is not one JSON object\n{said}"
    return out


class QuickRuns:
    """The ``--quick`` runs of one benchmark (one subclass per script, below)."""

    script: Path

    def test_docstring_states_the_quick_mode(self) -> None:
        doc = ast.get_docstring(ast.parse(self.script.read_text(encoding="utf-8"))) or ""
        assert "--quick" in doc, f"{self.script.name}: the docstring does not state --quick"

    def test_quick_run(self, extra: tuple[str, ...], tmp_path: Path) -> None:
        out = run_quick(self.script, extra, tmp_path)
        assert out.get("quick") is True, f'{self.script.name}: no "quick": true in {out}'
        run = (self.script.stem, extra)
        if isinstance(out.get("skipped"), str):
            assert run in MAY_SKIP, f"{self.script.name} skipped: {out['skipped']}"
            pytest.skip(f"{self.script.name}: {out['skipped']}")
        check = CHECKS.get(run)
        if check is not None:
            check(out)
        written = sorted(p.name for p in tmp_path.iterdir() if p.name != "numba-cache")
        assert not written, f"{self.script.name} wrote into its working folder: {written}"


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    if "extra" in metafunc.fixturenames and metafunc.cls is not None:
        runs = [(), *EXTRA_RUNS.get(metafunc.cls.script.stem, ())]
        ids = ["_".join(a.lstrip("-") for a in ("--quick", *r)) for r in runs]
        metafunc.parametrize("extra", runs, ids=ids)


for _script in SCRIPTS:
    globals()[f"Test_{_script.stem}"] = type(
        f"Test_{_script.stem}", (QuickRuns,), {"script": _script}
    )
