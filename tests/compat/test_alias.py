"""``import pddlstream...`` resolved to the compatibility tree, and the module tree itself."""

from __future__ import annotations

import importlib
import subprocess
import sys
import types
from pathlib import Path

import pytest

import sdar_tamp.compat.pddlstream as flat
from sdar_tamp.compat.pddlstream.alias import (
    AliasError,
    install_alias,
    is_installed,
    uninstall_alias,
)

ROOT = Path(__file__).resolve().parents[2]

#: (module, name) pairs PDDLStream programs import; each must exist under the prefix
SURFACE = {
    "algorithms.meta": [
        "solve",
        "create_parser",
        "ALGORITHMS",
        "FOCUSED_ALGORITHMS",
        "analyze_goal",
    ],
    "algorithms.focused": ["solve_focused", "solve_adaptive", "solve_binding"],
    "algorithms.incremental": ["solve_incremental"],
    "algorithms.search": ["solve_from_pddl"],
    "algorithms.constraints": ["PlanConstraints", "WILD"],
    "algorithms.downward": ["get_cost_scale", "set_cost_scale", "MAX_FD_COST"],
    "algorithms.satisfaction": [
        "constraint_satisfaction",
        "dump_assignment",
        "SatisfactionProblem",
        "SatisfactionSolution",
    ],
    "algorithms.instantiate_task": ["FD_INSTANTIATE"],
    "algorithms.instantiation": ["USE_RELATION"],
    "algorithms.refinement": ["CONSTRAIN_PLANS"],
    "algorithms.visualization": ["VISUALIZATIONS_DIR"],
    "language.generator": [
        "from_gen_fn",
        "from_fn",
        "from_test",
        "from_list_fn",
        "from_gen",
        "from_sampler",
        "universe_test",
        "empty_test",
        "outputs_from_boolean",
        "fn_from_constant",
        "empty_gen",
    ],
    "language.constants": [
        "PDDLProblem",
        "print_solution",
        "And",
        "Or",
        "Exists",
        "Equal",
        "Output",
        "Fact",
        "TOTAL_COST",
        "read_pddl_pair",
        "read_pddlstream_pair",
        "get_length",
        "is_parameter",
    ],
    "language.stream": ["StreamInfo", "DEBUG", "SHARED_DEBUG", "PartialInputs", "WildOutput"],
    "language.function": ["FunctionInfo", "PredicateInfo", "add_opt_function"],
    "language.external": [
        "defer_shared",
        "defer_unique",
        "never_defer",
        "get_defer_all_unbound",
        "get_defer_any_unbound",
    ],
    "language.temporal": ["retime_plan", "get_end", "compute_duration"],
    "language.exogenous": ["EXOGENOUS_AXIOMS", "REPLACE_STREAM"],
    "language.object": ["UniqueOptValue", "SharedOptValue", "DebugValue"],
    "language.optimizer": ["OptimizerOutput"],
    "retired.satisfaction": ["solve_pddlstream_satisfaction"],
    "utils": [
        "read",
        "INF",
        "get_file_path",
        "Profiler",
        "user_input",
        "str_from_object",
        "str_eq",
        "safe_zip",
        "randomize",
        "inclusive_range",
        "SEPARATOR",
        "flatten",
        "elapsed_time",
        "implies",
        "irange",
        "find_unique",
        "value_or_id",
    ],
}


@pytest.mark.parametrize("module", sorted(SURFACE))
def test_every_module_and_name_exists_under_the_prefix(module: str) -> None:
    loaded = importlib.import_module(f"sdar_tamp.compat.pddlstream.{module}")
    missing = [name for name in SURFACE[module] if not hasattr(loaded, name)]
    assert missing == []


def test_flat_surface_has_the_solver_entry_points() -> None:
    for name in (
        "solve",
        "solve_incremental",
        "solve_focused",
        "solve_from_pddl",
        "read_pddl_pair",
        "StreamInfo",
        "PDDLProblem",
        "constraint_satisfaction",
    ):
        assert name in flat.__all__ and hasattr(flat, name)


def test_alias_gives_the_same_module_objects() -> None:
    install_alias()
    try:
        assert is_installed()
        generator = importlib.import_module("pddlstream.language.generator")
        real = importlib.import_module("sdar_tamp.compat.pddlstream.language.generator")
        assert generator is real
        assert real.__spec__ is not None
        assert real.__spec__.name == "sdar_tamp.compat.pddlstream.language.generator"
        refinement = importlib.import_module("pddlstream.algorithms.refinement")
        refinement.CONSTRAIN_PLANS = True  # a program's module flag lands on the shared module
        from sdar_tamp.compat.pddlstream.algorithms import refinement as same

        assert same.CONSTRAIN_PLANS is True
        refinement.CONSTRAIN_PLANS = False
        with pytest.raises(ModuleNotFoundError):
            importlib.import_module("pddlstream.no_such_module")
    finally:
        uninstall_alias()
    assert not is_installed()
    assert "pddlstream" not in sys.modules


def test_alias_refuses_when_a_real_pddlstream_is_loaded(monkeypatch: pytest.MonkeyPatch) -> None:
    fake = types.ModuleType("pddlstream")
    fake.__file__ = "/elsewhere/pddlstream/__init__.py"
    monkeypatch.setitem(sys.modules, "pddlstream", fake)
    with pytest.raises(AliasError, match="already imported"):
        install_alias()
    assert not is_installed()


PROGRAM = """
from pddlstream.algorithms.meta import solve, create_parser
from pddlstream.language.constants import PDDLProblem, print_solution
from pddlstream.language.generator import from_gen_fn, from_test
from compat_domains import DOMAIN, STREAMS, INIT, GOAL, sample_pose

args = create_parser().parse_args()
stream_map = {"sample-pose": from_gen_fn(sample_pose),
              "test-safe": from_test(lambda b, p: p >= 2.0), "lift": lambda b: 2.0,
              "not-declared": from_test(lambda: True)}
problem = PDDLProblem(DOMAIN, {}, STREAMS, stream_map, INIT, GOAL)
print_solution(solve(problem, algorithm=args.algorithm, planner="max-astar", debug=True,
                     visualize=False, replan_actions={"pick"}, hierarchy=[]))
"""


def test_runner_runs_an_unmodified_program_and_rechecks_its_plan(tmp_path: Path) -> None:
    import json

    program = tmp_path / "program.py"
    program.write_text(PROGRAM)
    report = tmp_path / "report.json"
    env = {"PYTHONPATH": f"{ROOT}:{Path(__file__).parent}", "PATH": "/usr/bin:/bin"}
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "sdar_tamp.compat.pddlstream",
            "--report",
            str(report),
            str(program),
            "-a",
            "focused",
        ],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert "Solved: True" in done.stdout
    calls = json.loads(report.read_text())["calls"]
    assert [(c["algorithm"], c["solved"], c["valid"]) for c in calls] == [("focused", True, True)]
    assert calls[0]["cpu_seconds"] > 0.0  # the solve's CPU time is recorded beside its time


def test_the_record_holds_each_call_when_the_program_is_killed(tmp_path: Path) -> None:
    import json

    program = tmp_path / "program.py"
    killed = PROGRAM.replace(
        "args = create_parser().parse_args()", "import os, signal\nargs = None"
    )
    killed = killed.replace("algorithm=args.algorithm", "algorithm='focused'")
    program.write_text(killed + "os.kill(os.getpid(), signal.SIGKILL)\n")
    report = tmp_path / "report.json"
    env = {"PYTHONPATH": f"{ROOT}:{Path(__file__).parent}", "PATH": "/usr/bin:/bin"}
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "sdar_tamp.compat.pddlstream",
            "--report",
            str(report),
            str(program),
        ],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=120,
    )
    assert done.returncode == -9  # killed: the final write never happened
    record = json.loads(report.read_text())
    assert record["finished"] is False
    assert [(c["algorithm"], c["solved"], c["valid"]) for c in record["calls"]] == [
        ("focused", True, True)
    ]
