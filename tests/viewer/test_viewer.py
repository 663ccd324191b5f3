"""The plan viewers: timeline maths, the HTML page, storyboards, ``sdar show``."""

from __future__ import annotations

import base64
import dataclasses
import gzip
import re
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from sdar_tamp.cli import main
from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.viewer import MissingDependencyError, write_html, write_storyboard
from sdar_tamp.viewer._story import grips, joint_curves, link_poses, pose7
from sdar_tamp.viewer._timeline import Timeline
from sdar_tamp.viewer.storyboard import COLUMNS, DPI, PANEL_SIZE, panel_grid
from sdar_tamp.world.instance import Instance, save_instance
from sdar_tamp.world.scene import load_scene
from sdar_tamp.world.transforms import inverse, pose_xyz_yaw, top_down_pose
from tests.viewer.conftest import OBJECTS, SIZE, broken, decode, page_json


# -- the timeline -------------------------------------------------------------------------------
def test_objects_follow_the_events(instance: Instance, plan: PlanFile) -> None:
    timeline = Timeline.build(instance, plan, load_scene())
    grasp = next(e.t for e in plan.events if e.type == "grasp")
    release = next(e.t for e in plan.events if e.type == "release")
    times = np.array([0.0, grasp, (grasp + release) / 2, release, plan.duration])
    poses, holder = timeline.object_poses(times)
    starts = [pose_xyz_yaw(o.start.x, o.start.y, SIZE[2] / 2, o.start.yaw) for o in OBJECTS]
    for i in range(3):  # resting at start until grasped (o2 never moves)
        np.testing.assert_allclose(poses[0, i], starts[i], atol=1e-9)
        np.testing.assert_allclose(poses[1, i], starts[i], atol=1e-6)
    np.testing.assert_allclose(poses[:, 2], np.repeat(starts[2][None], 5, 0), atol=1e-9)
    assert holder.tolist() == [[-1, -1, -1], [0, 1, -1], [0, 1, -1], [-1, -1, -1], [-1, -1, -1]]
    # carried rigidly: the pose in the tool frame is the event's T_tcp_object
    q = timeline.q_at(times[2:3])
    for a in range(2):
        tcp = timeline.arms[a].tcp_poses(timeline.arm_q(q, a))[0]
        held = inverse(tcp) @ poses[2, a]
        np.testing.assert_allclose(held, plan.events[a].T_tcp_object, atol=1e-9)
    # released where the plan says, which is the goal; resting there afterwards
    for i in range(2):
        x, y, yaw = plan.final_poses[OBJECTS[i].name]
        goal = OBJECTS[i].goal
        np.testing.assert_allclose([x, y], [goal.x, goal.y], atol=1e-6)
        np.testing.assert_allclose(poses[3, i, :2, 3], [x, y], atol=1e-9)
        np.testing.assert_allclose(poses[4, i], poses[3, i], atol=1e-12)
        assert np.arctan2(poses[4, i, 1, 0], poses[4, i, 0, 0]) == pytest.approx(yaw, abs=1e-9)


def test_frames_are_sampled_at_fps(instance: Instance, plan: PlanFile) -> None:
    timeline = Timeline.build(instance, plan, load_scene())
    times = timeline.sample_times(10.0)
    assert times[0] == 0.0 and times[-1] == pytest.approx(plan.duration)
    assert np.all(np.diff(times) <= 0.1 + 1e-9)
    assert len(times) == int(np.floor(plan.duration * 10 + 1e-9)) + 1 + (
        plan.duration * 10 % 1 > 1e-6
    )
    with pytest.raises(ParameterError, match="fps must be > 0"):
        timeline.sample_times(0.0)


def test_unknown_event_object_is_named(instance: Instance, plan: PlanFile) -> None:
    event = dataclasses.replace(plan.events[0], object="ghost")
    bad = dataclasses.replace(plan, events=(event, *plan.events[1:]))
    with pytest.raises(ParameterError, match=r"plan.events\[0\].object 'ghost'"):
        Timeline.build(instance, bad, load_scene())


def test_plan_arms_must_match_the_scene(instance: Instance, plan: PlanFile) -> None:
    twins = dataclasses.replace(plan, arms=(plan.arms[0], plan.arms[0]))
    with pytest.raises(ParameterError, match=r"plan.arms: arm layout: arm names must differ"):
        Timeline.build(instance, twins, load_scene())
    one = dataclasses.replace(plan, arms=plan.arms[:1])
    with pytest.raises(ParameterError, match=r"plan.arms: expected 2 arms \(the scene's\), got 1"):
        Timeline.build(instance, one, load_scene())


def test_arm_joints_come_from_the_layout(instance: Instance, plan: PlanFile) -> None:
    timeline = Timeline.build(instance, plan, load_scene())
    assert timeline.layout == plan.layout
    q = timeline.q_at(np.array([0.0, plan.duration]))
    np.testing.assert_array_equal(timeline.arm_q(q, 1), q[:, timeline.layout.slice("right")])


# -- the HTML page ------------------------------------------------------------------------------
def test_html_is_self_contained_with_link_poses_per_frame(
    instance: Instance, plan: PlanFile, tmp_path: Path
) -> None:
    out = write_html(instance, plan, tmp_path / "deep" / "replay.html", fps=5)
    html = out.read_text(encoding="utf-8")
    assert not re.search(r"<script[^>]*src=[\"']?(https?:)?//", html)
    assert "<link" not in html  # no stylesheets fetched either
    packed = re.search(r'id="sdar-plotly">([A-Za-z0-9+/=\s]+)</script>', html)
    assert packed is not None  # plotly.js embedded, gzip + base64
    assert b"Plotly" in gzip.decompress(base64.b64decode(packed.group(1)))[:5000]
    data = page_json(html)
    expected = Timeline.build(instance, plan, load_scene()).sample_times(5)
    np.testing.assert_allclose(data["times"], expected, atol=1e-4)
    for arm in data["arms"]:  # one pose per link per frame, geometry sent once
        n_links, n_vertices = len(arm["links"]), len(decode(arm["vlink"]))
        assert len(decode(arm["poses"])) == len(expected) * n_links * 7
        assert len(decode(arm["local"])) == 3 * n_vertices
        assert len(decode(arm["tcp"])) == 7 * len(expected)
    assert [s["t_start"] for s in data["steps"]] == [s.t_start for s in plan.steps]
    assert [s["kind"] for s in data["steps"]] == [s.kind for s in plan.steps]
    assert [(e["t"], e["type"], e["object"]) for e in data["events"]] == [
        (e.t, e.type, e.object) for e in plan.events
    ]
    assert data["validated"] is True and data["violation"] is None
    assert len(data["joints"]["data"]) == 4 * 6  # q and q-dot of six joints, two arms
    assert out.stat().st_size < 2_500_000


def test_poses_round_trip_through_quaternions() -> None:
    angles = np.linspace(0.0, 2 * np.pi, 9)
    T = np.stack([top_down_pose(0.1 * a, -0.2, 0.3, a) for a in angles])
    T[3] = pose_xyz_yaw(0.0, 0.0, 0.0, 2.0)
    p = pose7(T)
    x, y, z, w = p[:, 3], p[:, 4], p[:, 5], p[:, 6]
    R = np.stack(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    ).transpose(2, 0, 1)
    np.testing.assert_allclose(R, T[:, :3, :3], atol=1e-12)
    np.testing.assert_allclose(p[:, :3], T[:, :3, 3])
    assert np.all(np.sum(p[1:, 3:] * p[:-1, 3:], axis=1) >= 0)  # no sign flips in a row


def test_grippers_close_on_the_object(instance: Instance, plan: PlanFile) -> None:
    timeline = Timeline.build(instance, plan, load_scene())
    grasp = next(e for e in plan.events if e.type == "grasp" and e.arm == plan.arms[0].name)
    release = next(e for e in plan.events if e.type == "release" and e.arm == plan.arms[0].name)
    times = np.array([0.0, grasp.t, grasp.t + 0.25, release.t - 0.1, release.t + 1.0])
    grip = grips(timeline, times)[0]
    np.testing.assert_allclose(grip.closure, [0.0, 0.0, 0.5, 1.0, 0.0])
    width = float(np.abs(grasp.T_tcp_object[1, :3]) @ np.asarray(SIZE))
    arm = timeline.arms[0].select(("base_link",), keep=False)
    T = link_poses(arm, timeline.arm_q(timeline.q_at(times), 0), grip)
    left, right = (arm.links.index(f) for f in ("gripper_left_finger", "gripper_right_finger"))
    gap = np.linalg.norm(T[:, left, :3, 3] - T[:, right, :3, 3], axis=1)
    thickness = 0.012  # the finger boxes of the shipped robot, across the jaws
    assert gap[0] == pytest.approx(2 * 0.036) and gap[4] == pytest.approx(2 * 0.036)
    assert gap[3] == pytest.approx(width + thickness)
    assert gap[2] == pytest.approx((gap[0] + gap[3]) / 2)


def test_joint_curves_against_the_limits(instance: Instance, plan: PlanFile) -> None:
    scene = load_scene()
    timeline = Timeline.build(instance, plan, scene)
    curves = joint_curves(timeline, scene)
    spec = scene.arms[0]
    lower, upper = spec.lower_array, spec.upper_array
    q = timeline.arm_q(timeline.q_at(curves.t), 0)
    np.testing.assert_allclose(curves.position[0], (q - lower) / (upper - lower), atol=1e-12)
    assert np.all((curves.position[0] >= 0) & (curves.position[0] <= 1))
    k = len(curves.t) // 3  # the velocity agrees with a finite difference of the positions
    dt = 1e-3
    qa, qb = (timeline.arm_q(timeline.q_at(np.array([curves.t[k] + s])), 0) for s in (-dt, dt))
    fd = (qb - qa)[0] / (2 * dt) / np.asarray(spec.velocity_limit)
    np.testing.assert_allclose(curves.velocity[0][k], fd, atol=0.02)
    assert np.abs(curves.velocity[0]).max() <= 1.0 + 1e-6


def test_the_first_violation_is_in_the_page(
    instance: Instance, plan: PlanFile, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    bad, t_jump = broken(plan)
    html = write_html(instance, bad, tmp_path / "bad.html").read_text(encoding="utf-8")
    violation = page_json(html)["violation"]
    assert violation is not None and "velocity" in violation["kind"]
    assert t_jump - 0.05 <= violation["t"] <= t_jump + 0.05
    assert "plan invalid at t=" in caplog.text
    unchecked = write_html(instance, bad, tmp_path / "unchecked.html", validate=False)
    data = page_json(unchecked.read_text(encoding="utf-8"))
    assert data["violation"] is None and data["validated"] is False


def test_html_without_plan_shows_the_start(instance: Instance, tmp_path: Path) -> None:
    html = write_html(instance, None, tmp_path / "start.html").read_text(encoding="utf-8")
    data = page_json(html)
    assert data["times"] == [0.0] and data["joints"] is None and data["steps"] == []
    assert "arm left" in html and "start (arms at home)" in html


def test_missing_dependencies_name_the_extra(
    instance: Instance, plan: PlanFile, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "plotly.offline", None)
    with pytest.raises(
        MissingDependencyError, match=r"needs plotly: pip install 'sdar-tamp\[viz\]'"
    ):
        write_html(instance, None, tmp_path / "x.html")
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(MissingDependencyError, match=r"needs matplotlib: pip install 'sdar-tamp"):
        write_storyboard(instance, plan, tmp_path / "x.png")


# -- storyboards ----------------------------------------------------------------------------------
def test_storyboard_has_one_panel_per_step(
    instance: Instance, plan: PlanFile, tmp_path: Path
) -> None:
    out = write_storyboard(instance, plan, tmp_path / "board.png")
    rows, cols = panel_grid(len(plan.steps))
    assert (rows, cols) == (-(-len(plan.steps) // COLUMNS), COLUMNS)
    with Image.open(out) as image:
        assert image.size == (cols * PANEL_SIZE[0] * DPI, rows * PANEL_SIZE[1] * DPI)
        colours = image.convert("RGB").getcolors(1 << 20)
    assert colours is not None and len(colours) > 100


def test_storyboard_without_steps_splits_at_releases(
    instance: Instance, plan: PlanFile, tmp_path: Path
) -> None:
    bare = dataclasses.replace(plan, steps=())
    segments = Timeline.build(instance, bare, load_scene()).segments()
    release = next(e.t for e in plan.events if e.type == "release")
    assert [(s.t_start, s.t_end) for s in segments] == [(0.0, release), (release, plan.duration)]
    with Image.open(write_storyboard(instance, bare, tmp_path / "bare.png")) as image:
        assert image.size == (2 * PANEL_SIZE[0] * DPI, PANEL_SIZE[1] * DPI)


def test_gif_has_one_frame_per_sample(instance: Instance, plan: PlanFile, tmp_path: Path) -> None:
    out = write_storyboard(instance, plan, tmp_path / "anim.gif", fps=2)
    expected = len(Timeline.build(instance, plan, load_scene()).sample_times(2))
    with Image.open(out) as image:
        assert image.n_frames == expected
        assert image.size == (PANEL_SIZE[0] * DPI, PANEL_SIZE[1] * DPI)


def test_storyboard_suffix_is_checked(instance: Instance, plan: PlanFile, tmp_path: Path) -> None:
    with pytest.raises(ParameterError, match=r"path must end in one of \.png, \.gif"):
        write_storyboard(instance, plan, tmp_path / "board.jpg")


# -- the command line -----------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["replay.html", "board.png", "anim.gif"])
def test_cli_show_with_a_plan(
    files: tuple[Path, Path], tmp_path: Path, name: str, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / name
    args = ["show", str(files[0]), str(files[1]), "-o", str(out)]
    assert main([*args, "--fps", "2"] if name.endswith(".gif") else args) == 0
    assert out.is_file() and f"wrote {out}" in capsys.readouterr().out


def test_cli_show_without_a_plan(
    files: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for name in ("start.png", "start.html"):
        assert main(["show", str(files[0]), "-o", str(tmp_path / name)]) == 0
        assert (tmp_path / name).is_file()
    assert main(["show", str(files[0]), "-o", str(tmp_path / "a.gif")]) == 2
    assert "a .gif animation needs a plan" in capsys.readouterr().err


def test_cli_show_errors(
    files: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["show", str(files[0]), str(files[1]), "-o", str(tmp_path / "x.pdf")]) == 2
    assert "output must end in one of .html, .png, .gif" in capsys.readouterr().err
    missing = tmp_path / "none.json"
    assert main(["show", str(files[0]), str(missing), "-o", str(tmp_path / "x.png")]) == 2
    assert "none.json" in capsys.readouterr().err
    other = tmp_path / "other.yaml"
    save_instance(Instance("W1", load_scene().workspace, OBJECTS[2:]), other)
    assert main(["show", str(other), str(files[1]), "-o", str(tmp_path / "x.png")]) == 2
    assert "'o0' is not an object of instance 'W1'" in capsys.readouterr().err
