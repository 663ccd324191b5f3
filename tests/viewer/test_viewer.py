"""The plan viewers: timeline maths, the HTML page, storyboards, ``sdar show``, a real browser."""

from __future__ import annotations

import base64
import dataclasses
import gzip
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image

from sdar_tamp.cli import main
from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_building import GripperEvent, MotionSegment, build_plan_file
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_writing import save_plan
from sdar_tamp.viewer import MissingDependencyError, write_html, write_storyboard
from sdar_tamp.viewer._story import grips, joint_curves, link_poses, pose7
from sdar_tamp.viewer._timeline import Timeline
from sdar_tamp.viewer.storyboard import COLUMNS, DPI, PANEL_SIZE, panel_grid
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D, load_instance, save_instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene, load_scene
from sdar_tamp.world.transforms import FloatArray, inverse, pose_xyz_yaw, top_down_pose

CHROMIUM = Path(shutil.which("chromium") or "/usr/bin/chromium")
SIZE = (0.08, 0.04, 0.05)
#: Left arm carries o0, right arm carries o1 (both at once); o2 starts at its goal.
OBJECTS = (
    ObjectSpec("o0", SIZE, Pose2D(-0.12, 0.12, 0.0), Pose2D(-0.12, -0.15, 0.6)),
    ObjectSpec("o1", SIZE, Pose2D(0.12, -0.12, 0.0), Pose2D(0.10, 0.15, 0.0)),
    ObjectSpec("o2", SIZE, Pose2D(0.0, 0.0, 0.3), Pose2D(0.0, 0.0, 0.3)),
)


# -- a hand-made plan: two simultaneous top-down pick-and-places ---------------------------------
def _ik(kin: ArmKinematics, pose: Pose2D, z: float, q_ref: FloatArray) -> FloatArray:
    q, ok = kin.ik_tcp(top_down_pose(pose.x, pose.y, z, pose.yaw)).closest(q_ref)
    assert ok[0], "fixture pose out of reach"
    return q[0]


def _move(
    q0: FloatArray, q1: FloatArray, duration: float, kind: str, objs: tuple[str, ...]
) -> MotionSegment:
    t = np.linspace(0.0, duration, round(duration / 0.02) + 1)
    s = 0.5 - 0.5 * np.cos(np.pi * t / duration)  # rest to rest
    return MotionSegment(t, q0 + s[:, None] * (q1 - q0), "free", objs, kind)


def build_plan(scene: Scene, instance: Instance, slow: float = 1.0) -> PlanFile:
    """About ``8 * slow`` seconds: approach, descend, grasp, lift, carry, lower, release,
    retreat and go home, both arms together."""
    kins = [ArmKinematics.from_scene(scene, a.name) for a in scene.arms]
    home = np.concatenate([np.array(a.home) for a in scene.arms])
    carried = (instance.objects[0], instance.objects[1])
    hover, z_grasp = 0.15, SIZE[2] / 2

    def both(which: str, z: float) -> FloatArray:
        out = home.copy()
        for a, (kin, obj) in enumerate(zip(kins, carried, strict=True)):
            out[6 * a : 6 * a + 6] = _ik(kin, getattr(obj, which), z, home[6 * a : 6 * a + 6])
        return out

    above_start, at_start = both("start", hover), both("start", z_grasp)
    above_goal, at_goal = both("goal", hover), both("goal", z_grasp)
    names = ("o0", "o1")
    grasps, releases = [], []
    for a, obj in enumerate(carried):
        T_obj = pose_xyz_yaw(obj.start.x, obj.start.y, z_grasp, obj.start.yaw)
        T_tcp = kins[a].fk_tcp(at_start[6 * a : 6 * a + 6])
        T_tcp_obj = inverse(T_tcp) @ T_obj
        grasps.append(GripperEvent(scene.arms[a].name, "grasp", obj.name, T_tcp_obj))
        releases.append(GripperEvent(scene.arms[a].name, "release", obj.name, T_tcp_obj))
    items = [
        _move(home, above_start, 1.5 * slow, "approach", names),
        _move(above_start, at_start, 0.6 * slow, "approach", names),
        *grasps,
        _move(at_start, above_start, 0.6 * slow, "transfer", names),
        _move(above_start, above_goal, 1.5 * slow, "transfer", names),
        _move(above_goal, at_goal, 0.6 * slow, "transfer", names),
        *releases,
        _move(at_goal, above_goal, 0.6 * slow, "retreat", names),
        _move(above_goal, home, 1.5 * slow, "retreat", names),
    ]
    starts = {o.name: o.start.as_tuple() for o in instance.objects}
    sizes = {o.name: o.size for o in instance.objects}
    return build_plan_file(scene, instance.name, starts, sizes, items, {"planning_time": 0.25})


def write_fixture(folder: Path, slow: float = 1.0) -> tuple[Path, Path]:
    """Write the instance and its plan; return both paths."""
    scene = load_scene()
    instance = Instance("V3", scene.workspace, OBJECTS)
    inst_path = save_instance(instance, folder / "V3.yaml")
    plan_path = save_plan(build_plan(scene, instance, slow), folder / "V3.plan.json")
    return inst_path, plan_path


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    return write_fixture(tmp_path_factory.mktemp("viewer"), slow=1.2)  # within the limits: valid


@pytest.fixture(scope="module")
def instance(files: tuple[Path, Path]) -> Instance:
    return load_instance(files[0])


@pytest.fixture(scope="module")
def plan(files: tuple[Path, Path]) -> PlanFile:
    return load_plan(files[1])


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
def page_json(html: str) -> dict[str, Any]:
    """The page's data: the JSON in its ``sdar-data`` script element."""
    m = re.search(r'<script type="application/json" id="sdar-data">(.*?)</script>', html, re.S)
    assert m is not None
    data = json.loads(m.group(1))
    assert isinstance(data, dict)
    return data


def decode(spec: dict[str, str]) -> np.ndarray:
    kind = {"f4": "<f4", "i4": "<i4", "u1": "u1"}[spec["dtype"]]
    return np.frombuffer(base64.b64decode(spec["bdata"]), dtype=np.dtype(kind))


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


def broken(plan: PlanFile) -> tuple[PlanFile, float]:
    """``plan`` with a jump of the first arm's shoulder in the middle: too fast there."""
    k = len(plan.t) // 2
    q = np.array(plan.q)
    q[k:, 0] += 0.3
    return dataclasses.replace(plan, q=q), float(plan.t[k])


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


# -- a real browser -------------------------------------------------------------------------------
def _chromium(url: str, workdir: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    profile = tempfile.mkdtemp(prefix="chromium-", dir=workdir)
    cmd = [
        str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
        "--no-first-run", "--disable-background-networking", "--disable-component-update",
        "--disable-sync", f"--user-data-dir={profile}", "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader", "--enable-logging=stderr", "--v=0",
        "--window-size=1200,900", "--virtual-time-budget=20000", "--hide-scrollbars",
        *extra, url,
    ]  # fmt: skip
    env = {**os.environ, "HOME": str(workdir)}
    return subprocess.run(cmd, capture_output=True, text=True, timeout=600, env=env, check=False)


needs_chromium = pytest.mark.skipif(
    not CHROMIUM.exists(), reason="chromium is not installed (apt-get install chromium)"
)


def _js_errors(stderr: str) -> list[str]:
    return [
        line
        for line in stderr.splitlines()
        if "Uncaught" in line or ("CONSOLE" in line and "Error" in line)
    ]


def _body(dom: str) -> dict[str, str]:
    """The attributes of the page's ``<body>`` after the run (the viewer's published state)."""
    m = re.search(r"<body([^>]*)>", dom)
    assert m is not None
    return dict(re.findall(r'([\w-]+)="([^"]*)"', m.group(1)))


def _with_script(page: Path, script: str) -> Path:
    """A copy of ``page`` running ``script`` once the viewer is ready (a user at the controls)."""
    html = page.read_text(encoding="utf-8")
    hook = "<script>window.addEventListener('sdar-ready', function () {" + script + "});</script>"
    out = page.with_name(page.stem + ".driven.html")
    out.write_text(html.replace("</body>", hook + "</body>"), encoding="utf-8")
    return out


@needs_chromium
def test_page_renders_in_headless_chromium(
    instance: Instance, plan: PlanFile, tmp_path: Path
) -> None:
    page = write_html(instance, plan, tmp_path / "replay.html", fps=5)
    t_mid = plan.duration / 2  # both arms carrying
    url = page.resolve().as_uri() + f"#t={t_mid:.2f}"
    started = time.monotonic()
    shot = tmp_path / "shot.png"
    run = _chromium(url, tmp_path, f"--screenshot={shot}", "--dump-dom")
    assert shot.is_file(), run.stderr[-2000:]
    assert not _js_errors(run.stderr), _js_errors(run.stderr)
    body = _body(run.stdout)
    assert body.get("data-sdar-ready") == str(len(page_json(page.read_text())["times"]))
    assert float(body["data-sdar-t"]) == pytest.approx(t_mid, abs=0.006)  # opened at #t=
    text = _visible_text(run.stdout)
    assert "WebGL" not in text and "could not" not in text
    assert re.search(r"left : gripper closed , holding o0", text), text[-600:]
    assert re.search(r"right : gripper closed , holding o1", text), text[-600:]
    assert "valid (sdar validate)" in text and 'id="sdar-banner" hidden' in run.stdout
    with Image.open(shot) as image:
        assert image.size == (1200, 900)
        view = np.asarray(image.convert("RGB"))[60:760, :740]  # the 3-D view
        panel = np.asarray(image.convert("RGB"))[60:760, 780:]  # the joint panel
    pixels = view.reshape(-1, 3)
    not_white = np.any(pixels < 235, axis=1).mean()
    distinct = len(np.unique(pixels // 8, axis=0))
    arms = [_near(pixels, (0x5B, 0x8F, 0xD1)), _near(pixels, (0xE0, 0x8A, 0x4F))]  # both arms
    assert not_white > 0.10 and distinct > 200 and min(arms) > 3000, (not_white, distinct, arms)
    curves = np.any(panel.reshape(-1, 3) < 200, axis=1).mean()
    assert curves > 0.01, curves  # the joint curves are drawn
    print(
        f"chromium: {time.monotonic() - started:.1f} s, {not_white:.0%} drawn, {distinct} colours"
    )


@needs_chromium
def test_step_buttons_and_speed_drive_the_time(
    instance: Instance, plan: PlanFile, tmp_path: Path
) -> None:
    page = write_html(instance, plan, tmp_path / "replay.html", fps=5)
    script = """
      var log = [], b = document.body;
      function note() {
        log.push(b.getAttribute('data-sdar-t') + '@' + b.getAttribute('data-sdar-step'));
      }
      note();
      document.getElementById('sdar-next').click(); note();
      document.getElementById('sdar-next').click(); note();
      document.getElementById('sdar-prev').click(); note();
      document.querySelectorAll('.sdar-step')[3].click(); note();
      var speed = document.getElementById('sdar-speed');
      speed.value = '4'; speed.dispatchEvent(new Event('change'));
      b.setAttribute('data-test-steps', String(document.querySelectorAll('.sdar-step').length));
      b.setAttribute('data-test-events', String(document.querySelectorAll('.sdar-ev').length));
      b.setAttribute('data-test-log', log.join(' '));
    """
    run = _chromium(_with_script(page, script).resolve().as_uri(), tmp_path, "--dump-dom")
    assert not _js_errors(run.stderr), _js_errors(run.stderr)
    body = _body(run.stdout)
    starts = [s.t_start for s in plan.steps]
    expected = [(0.0, 0), (starts[1], 1), (starts[2], 2), (starts[1], 1), (starts[3], 3)]
    log = [(float(t), int(k)) for t, k in (e.split("@") for e in body["data-test-log"].split())]
    assert [k for _, k in log] == [k for _, k in expected]
    np.testing.assert_allclose([t for t, _ in log], [t for t, _ in expected], atol=0.001)
    assert body["data-sdar-speed"] == "4"
    assert body["data-test-steps"] == str(len(plan.steps))
    assert body["data-test-events"] == str(len(plan.events))


@needs_chromium
def test_banner_shows_the_first_violation(
    instance: Instance, plan: PlanFile, tmp_path: Path
) -> None:
    bad, _ = broken(plan)
    page = write_html(instance, bad, tmp_path / "bad.html", fps=5)
    violation = page_json(page.read_text(encoding="utf-8"))["violation"]
    script = "document.getElementById('sdar-goto').click();"
    shot = tmp_path / "bad.png"
    run = _chromium(
        _with_script(page, script).resolve().as_uri(),
        tmp_path,
        f"--screenshot={shot}",
        "--dump-dom",
    )
    assert not _js_errors(run.stderr), _js_errors(run.stderr)
    banner = re.search(r'<div id="sdar-banner"([^>]*)>(.*?)</div>', run.stdout, re.S)
    assert banner is not None and "hidden" not in banner.group(1)
    assert f'data-kind="{violation["kind"]}"' in banner.group(1)
    assert f"invalid at t = {violation['t']:.2f} s" in banner.group(2)
    assert 'id="sdar-violation-mark"' in run.stdout  # on the time line
    assert float(_body(run.stdout)["data-sdar-t"]) == pytest.approx(violation["t"], abs=0.001)
    with Image.open(shot) as image:  # the banner is drawn: a red strip at the top
        top = np.asarray(image.convert("RGB"))[2:20, 200:1000].reshape(-1, 3).astype(int)
    red = (top[:, 0] > 150) & (top[:, 1] < 90) & (top[:, 2] < 90)
    assert red.mean() > 0.5, red.mean()


@needs_chromium
def test_a_browser_that_cannot_unpack_the_page_is_told(
    instance: Instance, plan: PlanFile, tmp_path: Path
) -> None:
    page = write_html(instance, plan, tmp_path / "replay.html", fps=5)
    old = page.with_name("old.html")
    html = page.read_text(encoding="utf-8")
    old.write_text(html.replace("<body>", "<body><script>window.DecompressionStream = undefined;"
                                "</script>", 1), encoding="utf-8")  # fmt: skip
    run = _chromium(old.resolve().as_uri(), tmp_path, "--dump-dom")
    banner = re.search(r'<div id="sdar-banner"([^>]*)>(.*?)</div>', run.stdout, re.S)
    assert banner is not None and "hidden" not in banner.group(1)
    assert "cannot unpack the page" in banner.group(2)
    assert "data-sdar-ready" not in _body(run.stdout)  # never drawn


def _near(pixels: np.ndarray, rgb: tuple[int, int, int], tol: int = 60) -> int:
    """Pixels within ``tol`` of the hue family of ``rgb`` (shading changes the brightness)."""
    p = pixels.astype(float)
    ref = np.array(rgb, dtype=float)
    cos = (p @ ref) / (np.linalg.norm(p, axis=1) * np.linalg.norm(ref) + 1e-9)
    spread = p.max(axis=1) - p.min(axis=1)
    return int(((cos > 0.985) & (spread > tol)).sum())


def _visible_text(dom: str) -> str:
    body = re.sub(r"<(script|style).*?</\1>", "", dom, flags=re.S)
    return re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", body))
