"""What is made from a k-arm plan: one URScript program per arm (each with every other arm's
base), a joint trajectory and CSV columns per arm, the viewer's page and pictures with one
timeline per arm, and the commands (`sdar validate`, `sdar export`, `sdar show`) on them."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.cli import main
from sdar_tamp.errors import ParameterError
from sdar_tamp.export import joint_trajectory_document, urscript_programs, write_csv
from sdar_tamp.export.timeline import base_to_base
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_writing import save_plan
from sdar_tamp.viewer import write_html, write_storyboard
from sdar_tamp.viewer._story import grips, joint_curves
from sdar_tamp.viewer._timeline import Timeline
from sdar_tamp.viewer.storyboard import ARM_COLOURS
from sdar_tamp.world.instance import Instance, save_instance
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import inverse

K = (1, 3, 4)


def _matrix_after(text: str, marker: str) -> np.ndarray:
    lines = text.splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith(marker))
    rows = [re.findall(r"-?\d+\.\d+", line) for line in lines[i + 1 : i + 5]]
    return np.array(rows, dtype=float)


@pytest.mark.parametrize("k", K)
def test_one_urscript_program_per_arm_with_every_other_base(
    k: int, plans: dict[int, PlanFile], cells: dict[int, Scene]
) -> None:
    plan = plans[k]
    programs = urscript_programs(plan, scene=cells[k])
    assert list(programs) == list(plan.arm_names)
    for i, (arm, text) in enumerate(programs.items()):
        assert f"def sdar_{arm}():" in text
        calls = re.findall(r'^  sdar_gripper_(close|open)\("(\w+)"\)$', text, re.M)
        assert calls == [
            ("close" if e.type == "grasp" else "open", e.object)
            for e in plan.events
            if e.arm == arm
        ]  # this arm's events, in order
        others = [j for j in range(k) if j != i]
        assert len(re.findall(r"^# T_\w+_\w+: ", text, re.M)) == len(others)
        for j in others:
            other = plan.arm_names[j]
            T = _matrix_after(text, f"# T_{arm}_{other}:")
            np.testing.assert_allclose(T, base_to_base(plan, i, j), atol=1e-6)
            expected = inverse(plan.arms[i].T_world_base) @ plan.arms[j].T_world_base
            np.testing.assert_allclose(T, expected, atol=1e-6)
        if k == 1:
            assert "# Start this program alone" in text
        else:
            assert "# Start this program and the other arms' together" in text


def test_base_to_base_names_a_bad_arm_index(plans: dict[int, PlanFile]) -> None:
    with pytest.raises(ParameterError, match=r"j: expected an arm index in \[0, 1\), got 1"):
        base_to_base(plans[1])
    with pytest.raises(ParameterError, match=r"i: expected an arm index in \[0, 4\), got -1"):
        base_to_base(plans[4], -1, 2)


@pytest.mark.parametrize("k", K)
def test_joint_trajectory_and_csv_per_arm(
    k: int, plans: dict[int, PlanFile], tmp_path: Path
) -> None:
    plan = plans[k]
    document = joint_trajectory_document(plan)
    assert [a["name"] for a in document["arms"]] == list(plan.arm_names)
    for i, arm in enumerate(document["arms"]):
        message = arm["joint_trajectory"]
        assert message["joint_names"] == list(plan.arms[i].joints)
        positions = np.array([p["positions"] for p in message["points"]])
        np.testing.assert_array_equal(positions, plan.q[:, plan.layout.slice(i)])
    assert len(document["gripper_commands"]) == len(plan.events) == 2 * k
    with write_csv(plan, tmp_path / "p.csv").open(encoding="utf-8") as stream:
        header = next(csv.reader(stream))
    assert len(header) == 1 + 6 * k + 2 * k
    assert header[-k:] == [f"{a}_held" for a in plan.arm_names]


@pytest.mark.parametrize("k", (3, 4))
def test_the_viewer_has_one_timeline_per_arm(
    k: int, plans: dict[int, PlanFile], cells: dict[int, Scene], instances: dict[int, Instance],
    tmp_path: Path,
) -> None:  # fmt: skip
    plan, scene, instance = plans[k], cells[k], instances[k]
    timeline = Timeline.build(instance, plan, scene)
    assert [a.name for a in timeline.arms] == list(plan.arm_names)
    times = timeline.sample_times(5.0)
    closed = grips(timeline, times)
    assert len(closed) == k
    t_grasp = next(e.t for e in plan.events if e.type == "grasp")
    for g in closed:  # every gripper closes at the one grasp instant
        assert g.closure[times < t_grasp].max() == 0.0 and g.closure.max() == 1.0
    curves = joint_curves(timeline, scene)
    assert len(curves.position) == k and all(p.shape[1] == 6 for p in curves.position)
    page = write_html(instance, plan, tmp_path / "k.html", scene, fps=4).read_text("utf-8")
    m = re.search(r'<script type="application/json" id="sdar-data">(.*?)</script>', page, re.S)
    assert m is not None
    data = json.loads(m.group(1))
    assert [a["name"] for a in data["arms"]] == list(plan.arm_names)
    assert len({a["colour"] for a in data["arms"]}) == k
    traces = data["traces"]["arms"]
    assert len(set(traces)) == k
    names = [data["figure"]["data"][i]["name"] for i in traces]
    assert names == [f"arm {a}" for a in plan.arm_names]
    assert data["figure"]["data"][data["traces"]["objects"]]["name"] == "objects"
    assert data["figure"]["data"][data["traces"]["labels"]]["name"] == "labels"
    assert {e["arm"] for e in data["events"]} == set(range(k))
    assert len(data["joints"]["data"]) == k * 2 * 6  # q and q-dot of six joints per arm
    assert data["validated"] is True and data["violation"] is None
    view = data["figure"]["layout"]["scene"]
    for axis, c in (("xaxis", 0), ("yaxis", 1)):  # every base in view, beyond the table too
        low, high = view[axis]["range"]
        bases = [a.T_world_base[c, 3] for a in scene.arms]
        assert low < min(bases) - 0.1 and max(bases) + 0.1 < high
    board = write_storyboard(instance, plan, tmp_path / "k.png", scene)
    assert board.stat().st_size > 0 and len(ARM_COLOURS) >= 4


def test_the_commands_on_a_four_arm_plan(
    plans: dict[int, PlanFile],
    cells: dict[int, Scene],
    instances: dict[int, Instance],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    scene = str(cells[4].file)
    instance = save_instance(instances[4], tmp_path / "K4.yaml")
    plan = save_plan(plans[4], tmp_path / "K4.plan.json")
    assert main(["validate", str(instance), str(plan), "--scene", scene, "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["valid"] is True
    out = tmp_path / "scripts"
    assert (
        main(["export", str(plan), "--format", "urscript", "-o", str(out), "--scene", scene]) == 0
    )
    assert sorted(p.name for p in out.iterdir()) == sorted(
        f"{a}.script" for a in cells[4].arm_names
    )
    capsys.readouterr()
    # the plan against the three-arm cell: a located error naming the arm counts
    assert main(["validate", str(instance), str(plan), "--scene", str(cells[3].file)]) != 0
    assert "arms: the cell has 3 arms, the plan 4" in capsys.readouterr().err


def test_the_pictures_draw_every_arm_and_reach_past_every_base(
    plans: dict[int, PlanFile], cells: dict[int, Scene], instances: dict[int, Instance]
) -> None:
    pytest.importorskip("matplotlib")
    from sdar_tamp.viewer.storyboard import MARGIN, _figure, _update, _view, arm_colour

    scene = cells[4]
    timeline = Timeline.build(instances[4], plans[4], scene)
    ax = _figure(4.0, 4.0).add_subplot()
    view = _view(ax, timeline, scene)
    _update(view, timeline, plans[4].duration / 2)
    assert len(view.arms) == len(view.jaws) == 4
    assert [line.get_color() for line in view.arms] == [arm_colour(a) for a in range(4)]
    assert all(len(line.get_xdata()) > 2 for line in view.arms)  # each arm drawn
    for limits, c in ((ax.get_xlim(), 0), (ax.get_ylim(), 1)):
        bases = [a.T_world_base[c, 3] for a in scene.arms]
        assert limits[0] <= min(bases) - MARGIN[0] + 1e-9
        assert limits[1] >= max(bases) + MARGIN[0] - 1e-9
    assert arm_colour(4) == arm_colour(0) != arm_colour(1)
