"""The plan viewers: timeline maths, the HTML page, storyboards, ``sdar show``, a real browser."""

from __future__ import annotations

import dataclasses
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from sdar_tamp.cli import main
from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import (
    GripperEvent,
    MotionSegment,
    PlanFile,
    build_plan_file,
    load_plan,
    save_plan,
)
from sdar_tamp.viewer import MissingDependencyError, write_html, write_storyboard
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
    return write_fixture(tmp_path_factory.mktemp("viewer"))


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
def _frames(html: str) -> list[dict[str, object]]:
    m = re.search(r"Plotly\.addFrames\('sdar-viewer', ", html)
    assert m is not None
    frames, _ = json.JSONDecoder().raw_decode(html[m.end() :])
    assert isinstance(frames, list)
    return frames


def test_html_is_self_contained_with_one_frame_per_sample(
    instance: Instance, plan: PlanFile, tmp_path: Path
) -> None:
    out = write_html(instance, plan, tmp_path / "deep" / "replay.html", fps=5)
    html = out.read_text(encoding="utf-8")
    assert not re.search(r"<script[^>]*src=[\"']?(https?:)?//", html)
    assert "<link" not in html  # no stylesheets fetched either
    assert html.count("<script") >= 2 and "Plotly.newPlot" in html  # plotly.js embedded
    frames = _frames(html)
    expected = Timeline.build(instance, plan, load_scene()).sample_times(5)
    assert len(frames) == len(expected) == len(set(str(f["name"]) for f in frames))
    assert len(re.findall(r'"method": ?"animate"', html)) == len(expected) + 2  # steps, buttons
    assert out.stat().st_size < 8_000_000


def test_html_without_plan_shows_the_start(instance: Instance, tmp_path: Path) -> None:
    html = write_html(instance, None, tmp_path / "start.html").read_text(encoding="utf-8")
    assert "Plotly.addFrames" not in html and "arm left" in html and "start (arms at home)" in html


def test_missing_dependencies_name_the_extra(
    instance: Instance, plan: PlanFile, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "plotly.io", None)
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
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120, env=env, check=False)


@pytest.mark.skipif(
    not CHROMIUM.exists(), reason="chromium is not installed (apt-get install chromium)"
)
def test_page_renders_in_headless_chromium(
    instance: Instance, plan: PlanFile, tmp_path: Path
) -> None:
    page = write_html(instance, plan, tmp_path / "replay.html", fps=5)
    url = page.resolve().as_uri() + f"#t={plan.duration / 2:.2f}"
    started = time.monotonic()
    shot = tmp_path / "shot.png"
    run = _chromium(url, tmp_path, f"--screenshot={shot}", "--dump-dom")
    assert shot.is_file(), run.stderr[-2000:]
    errors = [
        line
        for line in run.stderr.splitlines()
        if "Uncaught" in line or ("CONSOLE" in line and "Error" in line)
    ]
    assert not errors, errors
    assert 'data-sdar-ready="' in run.stdout, run.stderr[-2000:]
    assert re.search(r'data-sdar-frame="\d+"', run.stdout)  # jumped to #t= by Plotly.animate
    assert "WebGL" not in _visible_text(run.stdout)
    with Image.open(shot) as image:
        assert image.size == (1200, 900)
        plot = np.asarray(image.convert("RGB"))[60:780]  # below the title, above the slider
    pixels = plot.reshape(-1, 3)
    not_white = np.any(pixels < 235, axis=1).mean()
    distinct = len(np.unique(pixels // 8, axis=0))
    arms = [_near(pixels, (0x5B, 0x8F, 0xD1)), _near(pixels, (0xE0, 0x8A, 0x4F))]  # both arms
    assert not_white > 0.10 and distinct > 200 and min(arms) > 3000, (not_white, distinct, arms)
    print(
        f"chromium: {time.monotonic() - started:.1f} s, {not_white:.0%} drawn, {distinct} colours"
    )


def _near(pixels: np.ndarray, rgb: tuple[int, int, int], tol: int = 60) -> int:
    """Pixels within ``tol`` of the hue family of ``rgb`` (shading changes the brightness)."""
    p = pixels.astype(float)
    ref = np.array(rgb, dtype=float)
    cos = (p @ ref) / (np.linalg.norm(p, axis=1) * np.linalg.norm(ref) + 1e-9)
    spread = p.max(axis=1) - p.min(axis=1)
    return int(((cos > 0.985) & (spread > tol)).sum())


def _visible_text(dom: str) -> str:
    body = re.sub(r"<script.*?</script>", "", dom, flags=re.S)
    return re.sub(r"<[^>]+>", " ", body)
