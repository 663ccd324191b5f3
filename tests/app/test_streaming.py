"""Streaming (``sdar solve --stream``, :func:`sdar_tamp.app.streaming.solve_stream`): the
streamed steps are the batch plan, checked step by step, on two and three arms."""

from __future__ import annotations

import itertools
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from sdar_tamp.app.pipeline import solve_instance
from sdar_tamp.app.stream_records import (
    end_record,
    header_record,
    plan_from_records,
    step_record,
)
from sdar_tamp.app.streaming import StepRejected, solve_stream
from sdar_tamp.cli import main
from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_rules import Violation
from sdar_tamp.plan_writing import plan_to_dict
from sdar_tamp.replay import validate_plan
from sdar_tamp.replay_steps import StepValidator
from sdar_tamp.resources import domain_file
from sdar_tamp.world.instance import load_instance

D4 = domain_file("dual_arm_rearrangement", "suites/paper/D4.yaml")  # two swaps, a few seconds
CELL_3 = domain_file("dual_arm_rearrangement", "cells/ur5e_table_3arm.yaml")
#: Metrics that time the run (they differ between any two runs).
TIMING = {"planning_time", "planning_time_selection", "planning_time_motion", "step_time_median"}


def _same_plan(streamed: PlanFile, batch: PlanFile) -> None:
    """Field by field, exactly; the metrics but the run's timings."""
    a, b = plan_to_dict(streamed), plan_to_dict(batch)
    assert a.keys() == b.keys()
    for key in a:
        if key == "metrics":
            assert {k: v for k, v in a[key].items() if k not in TIMING} == {
                k: v for k, v in b[key].items() if k not in TIMING
            }
            assert a[key].keys() == b[key].keys()
        else:
            assert a[key] == b[key], key


def _lines(text: str) -> list[dict[str, Any]]:
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def test_cli_stream_is_the_batch_plan_and_validates(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    streamed_file, batch_file = tmp_path / "stream.json", tmp_path / "batch.json"
    args = ["solve", str(D4), "--seed", "0", "--time-limit", "600", "-q"]
    assert main([*args, "--stream", "-o", str(streamed_file)]) == 0
    captured = capsys.readouterr()
    records = _lines(captured.out)
    assert "D4: solved, plan valid" in captured.err and "wrote" in captured.err
    assert [r["type"] for r in records] == ["header"] + ["step"] * (len(records) - 2) + ["end"]
    header = records[0]
    assert header["instance"] == "D4" and header["execution"] == "sync"
    assert [a["name"] for a in header["arms"]] == ["left", "right"]
    assert all(len(a["joints"]) == 6 for a in header["arms"])
    steps = records[1:-1]
    assert [s["index"] for s in steps] == list(range(len(steps))) and len(steps) >= 2
    assert all(s["task"]["kind"] and s["events"] and s["steps"] for s in steps)
    times = [s["planned_at"] for s in steps]
    assert times == sorted(times)
    assert records[-1]["status"] == "solved" and records[-1]["valid"] is True
    # each step starts after the one before: absolute times, no overlap
    for before, after in itertools.pairwise(steps):
        assert after["trajectory"]["t"][0] > before["trajectory"]["t"][-1]
    rebuilt = plan_from_records(records)
    assert main([*args, "--execution", "sync", "-o", str(batch_file)]) == 0
    capsys.readouterr()
    _same_plan(rebuilt, load_plan(batch_file))
    _same_plan(load_plan(streamed_file), rebuilt)  # -o: the streamed plan, whole
    instance = load_instance(D4)
    assert validate_plan(instance, rebuilt).ok


def test_three_arm_table_stream_is_the_batch_plan(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    made = tmp_path / "M5.yaml"
    assert main(["generate", "--family", "M", "--objects", "5", "--seed", "1",
                 "--scene", str(CELL_3), "-o", str(made)]) == 0  # fmt: skip
    capsys.readouterr()
    stream = solve_stream(made, seed=0, time_limit=600.0)
    assert [a.name for a in stream.header.arms] == ["south", "north", "west"]
    records = [header_record(stream.header)]
    for step in stream:
        records.append(json.loads(json.dumps(step_record(step))))
    outcome = stream.outcome
    assert outcome is not None and outcome.success and outcome.plan is not None
    records.append(end_record(outcome.status, stream.last_part, outcome.plan, outcome.valid))
    rebuilt = plan_from_records(json.loads(json.dumps(records)))
    batch = solve_instance(made, seed=0, time_limit=600.0, execution="sync")
    assert batch.success and batch.plan is not None
    _same_plan(rebuilt, batch.plan)
    assert len({a for r in records[1:-1] for a in r["task"]["arms"]}) == 3  # every arm works
    assert validate_plan(load_instance(made), rebuilt).ok


def test_three_arm_cycle_gripper_events_at_one_instant_stream_alike() -> None:
    cycle = Path(__file__).parents[1] / "sdar" / "data" / "three_arm_cycle.yaml"
    stream = solve_stream(cycle, time_limit=600.0)
    steps = list(stream)
    assert stream.outcome is not None and stream.outcome.plan is not None
    grasps = [e for s in steps for e in s.part.events if e.type == "grasp"]
    assert len(grasps) == 3 and len({e.t for e in grasps}) == 1
    batch = solve_instance(cycle, time_limit=600.0, execution="sync")
    assert batch.plan is not None
    _same_plan(stream.outcome.plan, batch.plan)


def test_a_rejected_step_stops_the_stream(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    def reject(self: StepValidator, t: Any, q: Any, events: Any) -> Violation:
        return Violation(float(t[-1]), "collision", "left_wrist with right_wrist")

    monkeypatch.setattr(StepValidator, "check", reject)
    with pytest.raises(StepRejected, match=r"step 0 rejected by the replay: t=.*collision"):
        next(iter(solve_stream(D4, time_limit=600.0)))
    assert main(["solve", str(D4), "--stream", "-q", "--time-limit", "600"]) == 1
    captured = capsys.readouterr()
    records = _lines(captured.out)
    assert [r["type"] for r in records] == ["header", "end"]  # no step emitted unchecked
    assert records[-1]["status"] == "rejected" and "left_wrist" in records[-1]["violation"]
    assert "step 0 rejected" in captured.err


def test_a_stream_is_iterated_once() -> None:
    stream = solve_stream(D4, time_limit=600.0)
    stream._iterated = True  # as after a first iteration
    with pytest.raises(ParameterError, match="iterated once"):
        next(iter(stream))


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--execution", "async"], "--stream emits the synchronous timing"),
        (["--json"], "--stream writes JSON lines already"),
    ],
)
def test_stream_option_errors(
    capsys: pytest.CaptureFixture[str], extra: list[str], message: str
) -> None:
    assert main(["solve", str(D4), "--stream", *extra]) != 0
    assert message in capsys.readouterr().err


# -- the records --------------------------------------------------------------------------------


def _header() -> dict[str, Any]:
    return {"type": "header", "format": "sdar-plan-stream", "version": 1}


@pytest.mark.parametrize(
    ("records", "message"),
    [
        ([], "starts with its header"),
        ([{"type": "step"}], "starts with its header"),
        ([{**_header(), "version": 9}], "expected format 'sdar-plan-stream' version 1"),
        ([_header(), {"type": "plan"}], "line 2: unexpected type 'plan'"),
        ([_header(), {"type": "end", "final_poses": {}}, {"type": "step"}], "after the end"),
        ([_header(), {"type": "step"}], "no end record"),
        ([_header(), {"type": "end", "status": "infeasible"}], "ended without a plan"),
    ],
)
def test_plan_from_records_errors(records: list[dict[str, Any]], message: str) -> None:
    with pytest.raises(ParameterError, match=message):
        plan_from_records(records)


def test_step_validator_errors_and_end_rules() -> None:
    instance = load_instance(D4)
    from sdar_tamp.world.scene import load_scene

    scene = load_scene(instance.scene_path(D4))
    with pytest.raises(ParameterError, match="max_tcp_step"):
        StepValidator(instance, scene, max_tcp_step=0.0)
    checker = StepValidator(instance, scene)
    home = np.asarray(scene.home)[None]
    with pytest.raises(ParameterError, match="needs t"):
        checker.check(np.zeros(2), home, ())
    with pytest.raises(ParameterError, match="the first stretch starts"):
        checker.check(np.array([0.5]), home, ())
    assert checker.check(np.zeros(1), home, ()) is None
    with pytest.raises(ParameterError, match="not after the last one"):
        checker.check(np.zeros(1), home, ())
    end = checker.finish()  # nothing moved: the objects are not at their goals
    assert end is not None and end.kind == "goal"


def test_an_unsolvable_instance_streams_no_step_and_says_why(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D, save_instance
    from sdar_tamp.world.scene import Workspace

    size = (0.08, 0.04, 0.05)
    starts = [Pose2D(0.0, 0.045 * (i - 1), 0.0) for i in range(3)]  # 5 mm apart: none can
    goals = [Pose2D(0.15 * (i - 1), -0.2, 0.0) for i in range(3)]  # be picked first
    objects = tuple(ObjectSpec(f"o{i}", size, starts[i], goals[i]) for i in range(3))
    workspace = Workspace((-0.25, 0.25), (-0.30, 0.30))
    path = save_instance(Instance("boxed", workspace, objects), tmp_path / "boxed.yaml")
    assert main(["solve", str(path), "--stream", "-q", "--time-limit", "600"]) == 1
    captured = capsys.readouterr()
    records = _lines(captured.out)
    assert [r["type"] for r in records] == ["header", "end"]
    end = records[-1]
    assert end["status"] == "infeasible" and end["valid"] is False and "final_poses" not in end
    assert any("can ever be picked first" in line for line in end["diagnosis"])
    assert "boxed: infeasible" in captured.err
    with pytest.raises(ParameterError, match="ended without a plan"):
        plan_from_records(records)
