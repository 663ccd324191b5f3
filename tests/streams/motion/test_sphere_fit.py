"""Spheres fitted to collision meshes: they cover every link's surface, their volume is
bounded by the convex hull's, the fit is deterministic and cached, and the shipped UR5e's
primitive model is what it was. The makers' meshes (``example-robot-data``'s UR10 and Panda)
are checked the same way when that package is installed (``pip install sdar-tamp[robots]``;
``EXAMPLE_ROBOT_DATA_SHARE`` may name its ``share`` directory)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.world._coal import hull_volume
from sdar_tamp.world.scene import load_scene
from sdar_tamp.world.urdf import example_robot_data_share
from streams._pin_geometry import Primitive, arm_primitives
from streams.motion import sphere_cache, sphere_fit
from streams.motion import spheres as spheres_module
from streams.motion.sphere_fit import (
    FitOptions,
    box_triangles,
    cylinder_triangles,
    enclosing_sphere,
    fit_spheres,
    subdivide,
    union_volume,
)
from streams.motion.spheres import (
    ArmSpheres,
    arm_spheres,
    box_spheres,
    cylinder_spheres,
    gripper_shapes,
    model_digest,
)

MESHES = Path(__file__).parent / "meshes"
MESH_ARM = MESHES / "mesharm" / "urdf" / "mesh_arm.urdf"


def surface_points(triangles: np.ndarray, n: int, seed: int) -> np.ndarray:
    return sphere_fit.surface_points(triangles, n, np.random.default_rng(seed))


def covered(points: np.ndarray, centre: np.ndarray, radius: np.ndarray) -> np.ndarray:
    d = np.linalg.norm(points[:, None] - centre[None], axis=-1)
    return np.any(d <= radius[None] + 1e-9, axis=1)


def link_triangles(prims: list[Primitive]) -> dict[tuple[int, str], np.ndarray]:
    """Each moving link's mesh triangles (joint frame)."""
    out: dict[tuple[int, str], list[np.ndarray]] = {}
    for p in prims:
        if p.joint != 0 and p.triangles is not None:
            out.setdefault((p.joint, p.link), []).append(p.triangles)
    return {k: np.concatenate(v) for k, v in out.items()}


def check_links(urdf: Path, package_dirs: tuple[Path, ...]) -> dict[str, tuple[float, float]]:
    """Per mesh link: (coverage of 4000 surface points, union volume / hull volume); asserts
    both bounds of the issue (99.9 %, 3x)."""
    model = arm_spheres(urdf, package_dirs=package_dirs)
    prims = list(arm_primitives(urdf, package_dirs))
    seen: dict[str, tuple[float, float]] = {}
    # the spheres of a joint's mesh links come out link by link, in the shapes' order
    start = {j: int(np.flatnonzero(model.joint == j)[0]) for j in set(model.joint.tolist())}
    for (joint, link), tri in link_triangles(prims).items():
        fit = fit_spheres(tri)
        n = len(fit.radius)
        centre = model.centre[start[joint] : start[joint] + n]
        radius = model.radius[start[joint] : start[joint] + n]
        np.testing.assert_array_equal(centre, fit.centre)
        start[joint] += n
        points = surface_points(tri, 4000, seed=11)
        coverage = float(covered(points, centre, radius).mean())
        ratio = union_volume(centre, radius) / hull_volume(tri.reshape(-1, 3))
        assert coverage >= 0.999, (link, coverage)
        assert ratio <= 3.0, (link, ratio)
        assert n <= FitOptions().max_spheres
        seen[link] = (coverage, ratio)
    return seen


def test_the_mesh_files_are_those_the_script_writes(tmp_path: Path) -> None:
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_meshes", MESHES / "make_meshes.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.write(tmp_path)
    for name in ("meshes/capsule.stl", "meshes/ell.obj", "urdf/mesh_arm.urdf"):
        written = (tmp_path / "mesharm" / name).read_bytes()
        assert written == (MESHES / "mesharm" / name).read_bytes(), name


def test_mesh_links_are_covered_within_three_hulls() -> None:
    seen = check_links(MESH_ARM, (MESHES,))
    assert set(seen) == {"link1", "link2", "hand"}


@pytest.mark.parametrize("coarse", [False, True])
def test_the_test_links_are_covered_inside_too(coarse: bool) -> None:
    """The fit covers surfaces; on the test arm's closed links the inside is covered too."""
    model = arm_spheres(MESH_ARM, coarse=coarse, package_dirs=(MESHES,))
    rng = np.random.default_rng(3)
    # the capsule of link1 (joint 1 frame): its 16-gon's inscribed radius, 0.2 m up
    p = rng.uniform([-0.04, -0.04, 0.01], [0.04, 0.04, 0.39], (20000, 3))
    z = p[:, 2] - 0.2
    inner = 0.04 * np.cos(np.pi / 16) * 0.999
    capsule = p[np.hypot(p[:, 0], p[:, 1]) ** 2 + (z - np.clip(z, -0.15, 0.15)) ** 2 <= inner**2]
    # the L of link2 (joint 2 frame)
    q = rng.uniform([0.0, -0.025, -0.025], [0.25, 0.15, 0.025], (20000, 3))
    ell = q[(q[:, 1] <= 0.025) | (q[:, 0] <= 0.05)]
    for joint, points in ((1, capsule), (2, ell)):
        mine = model.joint == joint
        assert len(points) > 5000
        assert covered(points, model.centre[mine], model.radius[mine]).all()


def test_the_fit_covers_every_triangle_exactly() -> None:
    tri = next(p.triangles for p in arm_primitives(MESH_ARM, (MESHES,)) if p.link == "link2")
    assert tri is not None
    fit = fit_spheres(tri)
    assert covered(tri.reshape(-1, 3), fit.centre, fit.radius).all()
    assert covered(surface_points(tri, 20000, seed=3), fit.centre, fit.radius).all()


def test_the_fit_is_deterministic() -> None:
    spheres_module._arm_spheres.cache_clear()
    first = arm_spheres(MESH_ARM, package_dirs=(MESHES,))
    spheres_module._arm_spheres.cache_clear()
    second = arm_spheres(MESH_ARM, package_dirs=(MESHES,))
    assert first is not second
    for a, b in ((first.joint, second.joint), (first.centre, second.centre)):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(first.radius, second.radius)


def test_models_are_cached_by_content(tmp_path: Path) -> None:
    import shutil

    shutil.copytree(MESHES / "mesharm", tmp_path / "mesharm")
    urdf = tmp_path / "mesharm" / "urdf" / "mesh_arm.urdf"
    digest = model_digest(urdf, (tmp_path,))
    first = arm_spheres(urdf, package_dirs=(tmp_path,))
    assert arm_spheres(urdf, package_dirs=(tmp_path,)) is first
    assert not first.radius.flags.writeable
    # a mesh file that changes changes the digest, and so the model
    ell = tmp_path / "mesharm" / "meshes" / "ell.obj"
    ell.write_text(ell.read_text(encoding="utf-8").replace("0.250000", "0.300000"), "utf-8")
    assert model_digest(urdf, (tmp_path,)) != digest
    changed = arm_spheres(urdf, package_dirs=(tmp_path,))
    assert changed is not first
    assert changed.centre[:, 0].max() > first.centre[:, 0].max()


def test_fitted_models_are_kept_on_disk(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("SDAR_TAMP_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv(sphere_cache.ENV_SWITCH, "1")
    spheres_module._arm_spheres.cache_clear()
    first = arm_spheres(MESH_ARM, package_dirs=(MESHES,))
    kept = sorted((tmp_path / "cache").glob("spheres-*.npz"))
    assert len(kept) == 1
    spheres_module._arm_spheres.cache_clear()

    def no_fit(*args: object) -> None:
        raise AssertionError("fitted again")

    monkeypatch.setattr(spheres_module, "_build", no_fit)
    second = arm_spheres(MESH_ARM, package_dirs=(MESHES,))
    np.testing.assert_array_equal(first.centre, second.centre)
    np.testing.assert_array_equal(first.radius, second.radius)
    np.testing.assert_array_equal(first.joint, second.joint)
    monkeypatch.undo()
    spheres_module._arm_spheres.cache_clear()


def test_a_broken_or_switched_off_disk_cache_is_skipped(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("SDAR_TAMP_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv(sphere_cache.ENV_SWITCH, "1")
    key = sphere_cache.cache_key("some model")
    sphere_cache.cache_path(key).parent.mkdir(parents=True)
    sphere_cache.cache_path(key).write_bytes(b"not an npz")
    assert sphere_cache.load(key) is None
    joint, centre, radius = np.array([1]), np.zeros((1, 3)), np.ones(1)
    np.savez(sphere_cache.cache_path(key), joint=joint, centre=np.zeros((2, 3)), radius=radius)
    assert sphere_cache.load(key) is None  # shapes that disagree
    sphere_cache.store(key, joint, centre, radius)
    stored = sphere_cache.load(key)
    assert stored is not None and np.array_equal(stored[2], radius)
    monkeypatch.setenv(sphere_cache.ENV_SWITCH, "off")
    assert sphere_cache.load(key) is None
    other = sphere_cache.cache_key("another model")
    sphere_cache.store(other, joint, centre, radius)
    assert not sphere_cache.cache_path(other).exists()
    # a cache folder that cannot be made: the model is not kept, and nothing is raised
    monkeypatch.setenv(sphere_cache.ENV_SWITCH, "1")
    (tmp_path / "file").write_text("", encoding="utf-8")
    monkeypatch.setenv("SDAR_TAMP_CACHE", str(tmp_path / "file" / "cache"))
    sphere_cache.store(other, joint, centre, radius)
    assert sphere_cache.load(other) is None


def test_spheres_per_link_are_bounded() -> None:
    for count in (1, 3):
        model = arm_spheres(MESH_ARM, package_dirs=(MESHES,), options=FitOptions(max_spheres=count))
        # link1 on joint 1; link2 and the hand on joint 2
        assert (model.joint == 1).sum() <= count
        assert (model.joint == 2).sum() <= 2 * count


def test_coarse_model_groups_the_links_fixed_to_the_last_joint() -> None:
    prims = [p for p in arm_primitives(MESH_ARM, (MESHES,)) if p.joint != 0]
    assert [p.link for p in gripper_shapes(prims)] == ["hand"]
    coarse = arm_spheres(MESH_ARM, coarse=True, package_dirs=(MESHES,))
    fine = arm_spheres(MESH_ARM, package_dirs=(MESHES,))
    assert len(coarse) < len(fine)
    hand = next(p for p in prims if p.link == "hand").triangles
    assert hand is not None
    on_joint_2 = coarse.joint == 2
    points = surface_points(hand, 4000, seed=5)
    assert covered(points, coarse.centre[on_joint_2], coarse.radius[on_joint_2]).all()
    # every mesh link is still covered by the coarse model
    for (joint, _), tri in link_triangles(prims).items():
        mine = coarse.joint == joint
        assert covered(surface_points(tri, 4000, 6), coarse.centre[mine], coarse.radius[mine]).all()


def test_a_turned_hand_gets_a_box_along_the_hand() -> None:
    """The Panda's hand is mounted turned by -45 deg about the flange: its coarse box follows
    the hand (points of every gripper shape covered) and is much smaller than the box along
    the joint frame's axes; the UR5e's gripper, along the joint frame, keeps its box."""
    urdf = Path("domains/dual_arm_rearrangement/robots/panda_hand.urdf")
    prims = [p for p in arm_primitives(urdf) if p.joint != 0]
    grip = gripper_shapes(prims)
    R, _, half = spheres_module._gripper_box(grip)
    assert not np.allclose(R, np.eye(3))
    axis_box = np.concatenate([spheres_module._corners(p) for p in grip])
    axis_volume = np.prod(axis_box.max(axis=0) - axis_box.min(axis=0))
    assert np.prod(2 * half) < 0.5 * axis_volume
    coarse = arm_spheres(urdf, coarse=True)
    tool = coarse.joint == 7
    rng = np.random.default_rng(3)
    for p in grip:
        local = rng.uniform(-1.0, 1.0, (500, 3)) * np.array(p.half)
        points = local @ p.T_joint_shape[:3, :3].T + p.T_joint_shape[:3, 3]
        assert covered(points, coarse.centre[tool], coarse.radius[tool]).all()
    ur = [p for p in arm_primitives(Path("domains/dual_arm_rearrangement/robots/ur5e_2f85.urdf"))]
    R_ur, _, _ = spheres_module._gripper_box(gripper_shapes([p for p in ur if p.joint != 0]))
    assert np.array_equal(R_ur, np.eye(3))


def test_a_bare_arm_has_no_gripper_box() -> None:
    prims = [p for p in arm_primitives(MESH_ARM, (MESHES,)) if p.link != "hand"]
    assert gripper_shapes(prims) == []


def _primitive_model(urdf: Path, coarse: bool) -> ArmSpheres:
    """The UR5e's sphere model as it was built from its primitives alone (the gripper by its
    links' name prefix), to compare with."""
    prims = [p for p in arm_primitives(urdf) if p.joint != 0]
    joints, centres, radii = [], [], []
    grip = [p for p in prims if p.name.startswith("gripper")] if coarse else []
    for p in prims:
        if p in grip:
            continue
        if p.kind == "cylinder":
            c, r = cylinder_spheres(p.half[0], p.half[2], 2.0 if coarse else 1.2)
        else:
            c, r = box_spheres(np.array(p.half))
        joints += [p.joint] * len(r)
        centres.append(c @ p.T_joint_shape[:3, :3].T + p.T_joint_shape[:3, 3])
        radii.append(r)
    if grip:
        corners = []
        for p in grip:
            h = np.array(p.half if p.kind == "box" else (p.half[0], p.half[0], p.half[2]))
            grid = np.array(np.meshgrid(*[[-1.0, 1.0]] * 3)).reshape(3, -1).T * h
            corners.append(grid @ p.T_joint_shape[:3, :3].T + p.T_joint_shape[:3, 3])
        allp = np.concatenate(corners)
        lo, hi = allp.min(axis=0), allp.max(axis=0)
        c, r = box_spheres((hi - lo) / 2.0)
        joints += [grip[0].joint] * len(r)
        centres.append(c @ np.eye(3).T + (lo + hi) / 2.0)
        radii.append(r)
    return ArmSpheres(np.array(joints), np.concatenate(centres), np.concatenate(radii))


@pytest.mark.parametrize("coarse", [False, True])
def test_the_shipped_arm_keeps_its_primitive_spheres(coarse: bool) -> None:
    urdf = load_scene().robot_urdf
    model = arm_spheres(urdf, coarse=coarse)
    expected = _primitive_model(urdf, coarse)
    np.testing.assert_array_equal(model.joint, expected.joint)
    np.testing.assert_array_equal(model.centre, expected.centre)
    np.testing.assert_array_equal(model.radius, expected.radius)
    assert len(model) == (25 if coarse else 47)


def test_fitting_every_shape_covers_the_shipped_primitives() -> None:
    urdf = load_scene().robot_urdf
    model = arm_spheres(urdf, fit="all")
    assert set(model.joint.tolist()) == {1, 2, 3, 4, 5, 6}
    rng = np.random.default_rng(8)
    for p in arm_primitives(urdf):
        if p.joint == 0:
            continue
        n = 3000
        if p.kind == "cylinder":  # the true surface: side and caps
            r, h = p.half[0], p.half[2]
            a = rng.uniform(0.0, 2.0 * np.pi, n)
            rho = np.where(rng.uniform(size=n) < 0.5, r, r * np.sqrt(rng.uniform(size=n)))
            z = np.where(rho == r, rng.uniform(-h, h, n), rng.choice([-h, h], n))
            local = np.stack([rho * np.cos(a), rho * np.sin(a), z], axis=1)
        else:
            local = surface_points(box_triangles(np.array(p.half)), n, seed=9)
        points = local @ p.T_joint_shape[:3, :3].T + p.T_joint_shape[:3, 3]
        mine = model.joint == p.joint
        assert covered(points, model.centre[mine], model.radius[mine]).mean() >= 0.999, p.name


def test_cylinder_triangles_stay_within_their_tolerance() -> None:
    tri, tolerance = cylinder_triangles(0.05, 0.1, sides=12)
    assert tolerance == pytest.approx(0.05 * (1 - np.cos(np.pi / 12)))
    assert np.allclose(np.linalg.norm(tri[..., :2], axis=-1)[tri[..., 2] != 0].max(), 0.05)
    assert hull_volume(tri.reshape(-1, 3)) < np.pi * 0.05**2 * 0.2


def test_subdivision_keeps_the_surface_and_bounds_the_edges() -> None:
    tri = box_triangles(np.array([0.1, 0.2, 0.3]))
    small = subdivide(tri, 0.05)
    edges = np.linalg.norm(small - np.roll(small, 1, axis=1), axis=2)
    assert edges.max() <= 0.05

    def area(t: np.ndarray) -> float:
        return float(np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum())

    assert area(small) == pytest.approx(area(tri))


def test_enclosing_sphere_holds_its_points_and_is_near_the_smallest() -> None:
    points = np.random.default_rng(1).normal(size=(500, 3))
    points /= np.linalg.norm(points, axis=1)[:, None]
    centre, radius = enclosing_sphere(points)
    assert np.linalg.norm(points - centre, axis=1).max() <= radius + 1e-12
    assert radius <= 1.05


def test_union_volume_of_one_and_two_spheres() -> None:
    one = union_volume(np.zeros((1, 3)), np.array([0.1]), resolution=60)
    assert one == pytest.approx(4.0 / 3.0 * np.pi * 0.1**3, rel=0.02)
    apart = union_volume(np.array([[0, 0, 0], [1.0, 0, 0]]), np.array([0.1, 0.1]), 80)
    same = union_volume(np.zeros((2, 3)), np.array([0.1, 0.1]), 60)
    assert apart == pytest.approx(2 * one, rel=0.05)
    assert same == pytest.approx(one)


def test_hull_volume_of_a_cube_and_of_flat_points() -> None:
    corners = np.array(np.meshgrid(*[[-1.0, 1.0]] * 3)).reshape(3, -1).T * 0.5
    assert hull_volume(corners) == pytest.approx(1.0)
    assert hull_volume(corners * [1.0, 1.0, 0.0]) == 0.0
    assert hull_volume(corners[:3]) == 0.0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"max_spheres": 0}, "max_spheres must be >= 1, got 0"),
        ({"volume_ratio": 0.5}, "volume_ratio must be a finite number >= 1, got 0.5"),
        ({"volume_ratio": float("nan")}, "volume_ratio must be a finite number >= 1"),
        ({"edge_fraction": 0.0}, r"edge_fraction must lie in \(0, 1\], got 0.0"),
    ],
)
def test_bad_fit_options_name_the_parameter(kwargs: dict[str, float], message: str) -> None:
    with pytest.raises(ParameterError, match=message):
        FitOptions(**kwargs)  # type: ignore[arg-type]


def test_bad_fit_inputs_are_errors() -> None:
    tri = box_triangles(np.array([0.1, 0.1, 0.1]))
    with pytest.raises(ParameterError, match="at least one triangle"):
        fit_spheres(np.zeros((0, 3, 3)))
    with pytest.raises(ParameterError, match="not finite"):
        fit_spheres(np.where(np.arange(3) == 0, np.nan, tri))
    with pytest.raises(ParameterError, match="tolerance must be a finite number >= 0"):
        fit_spheres(tri, tolerance=-1.0)
    with pytest.raises(ParameterError, match=r"max_edge must be > 0 \[m\], got 0.0"):
        subdivide(tri, 0.0)
    with pytest.raises(ParameterError, match="fit must be one of meshes, all, got 'some'"):
        arm_spheres(MESH_ARM, package_dirs=(MESHES,), fit="some")


def test_a_missing_mesh_is_located(tmp_path: Path) -> None:
    from sdar_tamp.world.errors import SceneError

    with pytest.raises(SceneError, match=r"mesh_arm\.urdf:\d+:\d+: mesh 'package://mesharm/"):
        arm_spheres(MESH_ARM, package_dirs=(tmp_path,))


def test_a_single_point_mesh_gets_one_sphere() -> None:
    fit = fit_spheres(np.zeros((1, 3, 3)))
    assert len(fit.radius) == 1 and fit.radius[0] == 0.0 and fit.hull_volume == 0.0


SHARE = example_robot_data_share()
NO_MAKERS = pytest.mark.skipif(SHARE is None, reason="example-robot-data is not installed")

LINKS = {
    "ur_description/urdf/ur10_robot.urdf": {
        "shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link", "wrist_2_link",
        "wrist_3_link",
    },
    "panda_description/urdf/panda.urdf": {f"panda_link{i}" for i in range(1, 8)} | {"panda_hand"},
}  # fmt: skip


@NO_MAKERS
@pytest.mark.parametrize("relative", sorted(LINKS))
def test_maker_mesh_links_are_covered_within_three_hulls(relative: str) -> None:
    assert SHARE is not None
    robots = SHARE / "example-robot-data" / "robots"
    assert set(check_links(robots / relative, (robots, SHARE))) == LINKS[relative]


@NO_MAKERS
def test_the_panda_coarse_model_boxes_its_hand_and_fingers() -> None:
    assert SHARE is not None
    robots = SHARE / "example-robot-data" / "robots"
    urdf = robots / "panda_description/urdf/panda.urdf"
    coarse = arm_spheres(urdf, coarse=True, package_dirs=(robots, SHARE))
    fine = arm_spheres(urdf, package_dirs=(robots, SHARE))
    # the fingers (joints 8, 9) and the hand join one box on joint 7
    assert set(coarse.joint.tolist()) == set(range(1, 8))
    assert set(fine.joint.tolist()) == set(range(1, 10))
