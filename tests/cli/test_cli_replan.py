"""``sdar replan``: the new plan written and valid, the JSON record, infeasible re-plans and
every bad input (exit status 2 with a located error)."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import pytest

from sdar_tamp.plan_reading import load_plan
from sdar_tamp.resources import domains_root
from tests.cli.conftest import run_cli

D5 = str(domains_root() / "dual_arm_rearrangement/suites/paper/D5.yaml")
PLAN = str(Path(__file__).parents[1] / "plan" / "solved" / "D5.plan.json")


def _observed(tmp_path: Path, text: str) -> str:
    path = tmp_path / "obs.yaml"
    path.write_text(text, encoding="utf-8")
    return str(path)


def test_replan_writes_a_valid_plan(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    obs = _observed(tmp_path, "removed: [o2]\n")
    new = tmp_path / "new.json"
    argv = ["replan", D5, PLAN, "--at", "4.5", "--observed", obs, "-o", str(new)]
    code, out, _ = run_cli(argv, capsys)
    assert code == 0, out
    assert out.startswith("repaired: cut at t = ") and "valid" in out and "wrote" in out
    assert "o2" not in load_plan(new).final_poses
    code, out, _ = run_cli(["validate", D5, str(new)], capsys)
    assert code == 0 and out.startswith("valid:")
    code, out, err = run_cli(argv, capsys)
    assert code == 2 and "exists" in err  # no overwrite without --force


def test_replan_json_and_infeasible(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """o1 nudged at 5.4 s, when the right arm is too close to brake before touching it."""
    obs = _observed(tmp_path, "poses: [{name: o1, pose: [-0.045, -0.064, 1.19]}]\n")
    code, out, _ = run_cli(["replan", D5, PLAN, "--at", "5.4", "--observed", obs, "--json"], capsys)
    record = json.loads(out)
    assert code == 1 and record["status"] == "infeasible" and record["blocking"] == ["o1"]
    assert record["plan_file"] is None and "before the arms can stop" in record["reasons"][0]
    code, out, _ = run_cli(["replan", D5, PLAN, "--at", "5.4", "--observed", obs], capsys)
    assert code == 1 and out.startswith("infeasible:") and "blocking: o1" in out


@pytest.mark.parametrize(
    ("text", "argv", "message"),
    [
        ("removed: [on]\n", [], "obs.yaml:1:11: removed[0]: expected a name, got 'on'"),
        ("removed: [o9]\n", [], "obs.yaml:1:11: unknown object 'o9'"),
        ("poses: [{name: o2, pose: [0.2, 0.04, 0]}]\n", [],
         "obs.yaml:1:16: objects 'o2' and 'o4' overlap by"),
        ("", ["--at", "-1"], "argument --at: "),
        ("", ["--at", "1e3"], "at: expected a time within the plan [0, 12.534] s"),
        ("", ["-o", "new.txt"], ".json"),
    ],
)  # fmt: skip
def test_replan_refuses_bad_input(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, argv: list[str], message: str
) -> None:
    obs = _observed(tmp_path, text)
    at = [] if "--at" in argv else ["--at", "4.5"]
    code, out, err = run_cli(["replan", D5, PLAN, *at, "--observed", obs, *argv], capsys)
    assert code == 2 and out == "", out
    assert message in err, err


def test_replan_missing_files(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    obs = _observed(tmp_path, "")
    for argv in (
        [D5, str(tmp_path / "none.json"), "--at", "1", "--observed", obs],
        [D5, PLAN, "--at", "1", "--observed", str(tmp_path / "none.yaml")],
    ):
        code, _, err = run_cli(["replan", *argv], capsys)
        assert code == 2 and "none." in err


def test_replan_no_compare_keeps_the_repair(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """o4 nudged at 5.116 s: by default the repair is compared with a fresh continuation,
    which is shorter and kept (the repair's duration reported as the alternative); with
    --no-compare the repair is kept and nothing is compared."""
    from sdar_tamp.plan_state import state_at
    from sdar_tamp.world.instance import load_instance
    from sdar_tamp.world.scene import load_scene

    instance = load_instance(Path(D5))
    starts = {o.name: o.start.as_tuple() for o in instance.objects}
    x, y, yaw = state_at(load_plan(PLAN), starts, load_scene(), 5.116).resting["o4"]
    obs = _observed(tmp_path, f"poses: [{{name: o4, pose: [{x + 0.0052}, {y + 0.0173}, "
                              f"{yaw - 0.1559}]}}]\n")  # fmt: skip
    argv = ["replan", D5, PLAN, "--at", "5.116", "--observed", obs, "--json"]
    code, out, _ = run_cli(argv, capsys)
    compared = json.loads(out)
    code_no, out_no, _ = run_cli([*argv, "--no-compare"], capsys)
    kept = json.loads(out_no)
    assert code == 0 and compared["status"] == "replanned" and compared["valid"] is True
    assert code_no == 0 and kept["status"] == "repaired" and kept["valid"] is True
    assert kept["alternative"] is None
    assert compared["alternative"] == pytest.approx(kept["execution_time"])
    assert compared["execution_time"] < kept["execution_time"]
    code, out, _ = run_cli(argv[:-1], capsys)
    assert code == 0 and "compared with: " in out and "(not kept)" in out


def test_replan_while_moving_writes_the_repair_first(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """o4 nudged at 5.116 s with --while-moving: the first record is the repair, valid and
    written; each next one, when a fresh continuation is found in time, is shorter than the
    one before and written over it. Where the arms already stand at the cut when the repair
    is ready, a fresh continuation found within the look replaces it as the only record
    (which one happens depends on the machine's speed). --while-moving with --fresh or
    --no-compare is refused."""
    from sdar_tamp.plan_state import state_at
    from sdar_tamp.world.instance import load_instance
    from sdar_tamp.world.scene import load_scene

    instance = load_instance(Path(D5))
    starts = {o.name: o.start.as_tuple() for o in instance.objects}
    x, y, yaw = state_at(load_plan(PLAN), starts, load_scene(), 5.116).resting["o4"]
    obs = _observed(tmp_path, f"poses: [{{name: o4, pose: [{x + 0.0052}, {y + 0.0173}, "
                              f"{yaw - 0.1559}]}}]\n")  # fmt: skip
    new = tmp_path / "new.json"
    argv = ["replan", D5, PLAN, "--at", "5.116", "--observed", obs, "--while-moving"]
    code, out, _ = run_cli([*argv, "--json", "-o", str(new)], capsys)
    records = [json.loads(line) for line in out.splitlines()]
    assert code == 0 and len(records) >= 1
    assert all(record["valid"] is True for record in records)
    if records[0]["status"] == "replanned":  # found within the look, at the cut
        (looked,) = records
        assert looked["execution_time"] < looked["alternative"]
    else:
        assert records[0]["status"] == "repaired"
    for before, later in itertools.pairwise(records):
        assert later["status"] == "replanned" and later["valid"] is True
        assert later["execution_time"] < before["execution_time"]
        assert later["alternative"] == pytest.approx(before["execution_time"])
    assert load_plan(new).duration == pytest.approx(records[-1]["execution_time"])
    for other in ("--fresh", "--no-compare"):
        code, _, err = run_cli([*argv, other], capsys)
        assert code == 2 and "not allowed with" in err
