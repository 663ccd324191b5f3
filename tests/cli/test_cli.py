"""The ``sdar`` command line: help, version, demo, plan, check and error paths."""

import json
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp import __version__
from sdar_tamp.cli import build_parser, main
from sdar_tamp.resources import domain_file


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.strip() == f"sdar {__version__}"


def test_every_subcommand_has_help(capsys: pytest.CaptureFixture[str]) -> None:
    parser = build_parser()
    subparsers = next(a for a in parser._actions if a.dest == "command")
    for name in subparsers.choices:  # type: ignore[union-attr]
        with pytest.raises(SystemExit) as info:
            main([name, "--help"])
        assert info.value.code == 0
        assert "usage: sdar" in capsys.readouterr().out


def test_demo_solves_validates_and_draws_the_mixed_instance(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    assert main(["demo", "--out", str(tmp_path), "--time-limit", "600"]) == 0
    out = capsys.readouterr().out
    assert "M1: solved, plan valid" in out and "per step: median" in out
    assert "s asynchronous (synchronous " in out  # as `sdar solve` executes by default
    for name in ("plan.json", "plan.html", "storyboard.png"):
        assert (tmp_path / name).stat().st_size > 1000
    assert main(["validate", str(domain_file("dual_arm_rearrangement", "suites/paper/M1.yaml")),
                 str(tmp_path / "plan.json")]) == 0  # fmt: skip


def test_solve_writes_a_plan_that_validates(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    # R4: four independent objects, planned in about a second (S4's swaps take seconds)
    instance = domain_file("dual_arm_rearrangement", "suites/paper/R4.yaml")
    plan = tmp_path / "R4.json"
    assert (
        main(
            [
                "solve",
                str(instance),
                "-o",
                str(plan),
                "--json",
                "--seed",
                "3",
                "--time-limit",
                "600",
            ]
        )
        == 0
    )
    captured = capsys.readouterr()
    record = json.loads(captured.out)  # --json: one object on stdout, no progress bar
    assert captured.err == ""
    assert (record["instance"], record["status"], record["valid"]) == ("R4", "solved", True)
    assert record["plan_file"] == str(plan) and record["metrics"]["actions"] >= 4
    assert record["figures"]["planning_time"] > 0 and record["violation"] is None
    bound, execution = record["bound"], record["metrics"]["execution_time"]
    assert bound["arms"] == 2 and bound["objects"] == 4 and bound["proven"]
    assert 0.0 < bound["seconds"] < execution
    assert bound["seconds"] == max(bound["sum_over_arms"], bound["longest_object"])
    assert bound["execution_over_bound"] == pytest.approx(execution / bound["seconds"])
    assert main(["validate", str(instance), str(plan)]) == 0
    data = json.loads(plan.read_text())
    assert data["format"] == "sdar-plan" and data["metrics"]["task_planner"] == "sdar"
    assert max(np.diff(data["trajectory"]["t"])) <= 0.02 + 1e-9


def test_solve_reports_failure_with_exit_status_1(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    instance = domain_file("dual_arm_rearrangement", "suites/paper/M2.yaml")
    assert main(["solve", str(instance), "-q", "--time-limit", "0.01"]) == 1
    out = capsys.readouterr().out
    assert "M2: timeout" in out and "execution-time bound " in out


def test_solve_rejects_a_bad_time_limit(capsys: pytest.CaptureFixture[str]) -> None:
    instance = domain_file("dual_arm_rearrangement", "suites/paper/S4.yaml")
    with pytest.raises(SystemExit) as info:
        main(["solve", str(instance), "--time-limit", "-1"])
    assert info.value.code == 2
    assert "--time-limit: expected a finite number > 0 [s], got '-1'" in capsys.readouterr().err


def test_plan_on_shipped_files(capsys: pytest.CaptureFixture[str]) -> None:
    domain = domain_file("blocksworld")
    problem = domain_file("blocksworld", "problems/sussman.pddl")
    assert main(["plan", str(domain), str(problem), "--search", "astar", "--heuristic", "max"]) == 0
    assert "length: 6" in capsys.readouterr().out


def test_plan_with_missing_file(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert main(["plan", str(tmp_path / "none.pddl"), str(tmp_path / "p.pddl")]) == 2
    assert "cannot read" in capsys.readouterr().err


def test_check_reports_located_errors(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    bad = tmp_path / "bad.pddl"
    bad.write_text("(define (domain d)\n  (:predicates (p ?x))\n  (:action a :effect (q)))")
    assert main(["check", str(bad)]) == 2
    assert f"{bad}:3:23: undeclared predicate 'q'" in capsys.readouterr().err


def test_check_summarises(capsys: pytest.CaptureFixture[str]) -> None:
    domain = domain_file("blocksworld")
    assert main(["check", str(domain)]) == 0
    assert "4 actions" in capsys.readouterr().out


def test_bad_search_name_is_an_error(capsys: pytest.CaptureFixture[str]) -> None:
    domain = domain_file("blocksworld")
    problem = domain_file("blocksworld", "problems/sussman.pddl")
    try:  # argparse's choices exit with 2
        code = main(["plan", str(domain), str(problem), "--search", "dfs"])
    except SystemExit as error:
        code = error.code
    assert code == 2
    assert "search" in capsys.readouterr().err


def test_unknown_shipped_domain() -> None:
    from sdar_tamp.errors import ParameterError

    with pytest.raises(ParameterError, match="domain must be one of"):
        domain_file("no-such-domain")


def test_generate_and_show(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from sdar_tamp.world.dependency import instance_dependency_graph
    from sdar_tamp.world.instance import load_instance

    out = tmp_path / "S8.yaml"
    assert main(["generate", "--family", "S", "--objects", "8", "--seed", "3", "-o", str(out)]) == 0
    instance = load_instance(out)
    assert len(instance.objects) == 8
    assert len(instance_dependency_graph(instance).structure().cycles) == 1
    picture = tmp_path / "S8.png"
    assert main(["show", str(out), "-o", str(picture)]) == 0
    assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_generate_needs_family_and_objects(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    assert main(["generate", "--objects", "3", "-o", str(tmp_path / "x.yaml")]) == 2
    assert "needs --family and --objects" in capsys.readouterr().err


def test_generate_rejects_a_bad_object_count(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    out = tmp_path / "x.yaml"
    assert main(["generate", "--family", "S", "--objects", "1", "-o", str(out)]) == 2
    assert "family S needs at least 2, got 1" in capsys.readouterr().err
    assert not out.exists()


def test_demo_writes_a_fresh_folder_per_run(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Without -o each demo run gets its own new folder under the temporary directory."""
    import tempfile

    import sdar_tamp.app.pipeline as command
    from sdar_tamp.app.records import RunFigures, SolveOutcome
    from sdar_tamp.world.instance import load_instance

    instance = load_instance(domain_file("dual_arm_rearrangement", "suites/paper/M1.yaml"))
    figures = RunFigures("sdar", "sdar", 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    failed = SolveOutcome(instance, "timeout", None, False, "no plan", figures)
    monkeypatch.setattr(command, "solve_instance", lambda *a, **k: failed)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    assert main(["demo"]) == 1 and main(["demo"]) == 1  # no plan: exit 1, folders made
    folders = sorted(p.name for p in tmp_path.iterdir())
    assert len(folders) == 2 and all(f.startswith("sdar-demo-") for f in folders)
    assert "M1: timeout" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("flags", "level"),
    [
        ([], "WARNING"),
        (["-v"], "INFO"),
        (["-vv"], "DEBUG"),
        (["-vvv", "--log-level", "error"], "ERROR"),
    ],
)
def test_log_level_options_set_the_package_logger(
    flags: list[str], level: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    import logging

    logger = logging.getLogger("sdar_tamp")
    monkeypatch.setattr(logger, "level", logging.NOTSET)  # restored after the test
    root = logging.getLogger()
    monkeypatch.setattr(root, "handlers", [])  # restored after the test
    assert main(["check", str(domain_file("blocksworld")), *flags]) == 0
    if level == "WARNING":  # no option: logging is left as it was (Python shows warnings)
        assert logger.level == logging.NOTSET and root.handlers == []
        return
    assert logging.getLevelName(logger.level) == level
    (handler,) = root.handlers
    handler.handle(logging.makeLogRecord({"msg": "to the stderr of the moment"}))


def test_an_unknown_log_level_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["check", str(domain_file("blocksworld")), "--log-level", "loud"])
    assert info.value.code == 2
    assert "argument --log-level: invalid choice: 'loud'" in capsys.readouterr().err
