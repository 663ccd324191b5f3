"""Robot descriptions with meshes and package:// URIs: resolution, loading, located errors."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.world._pin import PinRobot
from sdar_tamp.world.collision_model import (
    build_dual_arm,
    build_scene_geometry,
    colliding_pairs,
    link_poses,
)
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.scene import default_scene_path, domain_path, load_scene
from sdar_tamp.world.transforms import translation
from sdar_tamp.world.urdf import package_dirs_from_env, read_urdf, resolve_package_uri
from streams._pin_geometry import arm_primitives

TET = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
TET_FACES = ((0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3))


def write_stl(path: Path, vertices: np.ndarray, faces: tuple[tuple[int, int, int], ...]) -> None:
    """An ASCII STL of the triangles ``faces`` over ``vertices`` ``(n, 3)``."""
    lines = ["solid mesh"]
    for a, b, c in faces:
        n = np.cross(vertices[b] - vertices[a], vertices[c] - vertices[a])
        n = n / np.linalg.norm(n)
        lines += [f"facet normal {n[0]} {n[1]} {n[2]}", "outer loop"]
        lines += [f"vertex {v[0]} {v[1]} {v[2]}" for v in vertices[[a, b, c]]]
        lines += ["endloop", "endfacet"]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join([*lines, "endsolid mesh", ""]), encoding="utf-8")


def write_box_obj(path: Path, half: tuple[float, float, float]) -> None:
    """A Wavefront OBJ of the box of half sides ``half`` centred at the origin."""
    corners = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    lines = [f"v {x * half[0]} {y * half[1]} {z * half[2]}" for x, y, z in corners]
    quads = ((1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4))
    lines += [f"f {a} {b} {c} {d}" for a, b, c, d in quads]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


TOY = """<?xml version="1.0"?>
<robot name="toy">
  <link name="base"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="link1">
    <collision>
      <origin xyz="0 0 0.1" rpy="0 0 0"/>
      <geometry><mesh filename="package://toyarm/meshes/tet.stl" scale="0.2 0.2 0.2"/></geometry>
    </collision>
  </link>
  <link name="link2">
    <collision><geometry><mesh filename="{box}"/></geometry></collision>
    <visual><geometry><mesh filename="package://elsewhere/link2.dae"/></geometry></visual>
  </link>
  <gazebo><plugin name="control" filename="libgazebo_ros_control.so"/></gazebo>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="link1"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>
  <joint name="j2" type="revolute">
    <parent link="link1"/><child link="link2"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="1" velocity="1"/>
  </joint>
</robot>
"""


def toy_arm(root: Path, box: str = "../meshes/box.obj") -> Path:
    """A two-link arm in the package folder ``root/toyarm`` with an STL and an OBJ mesh."""
    package = root / "toyarm"
    write_stl(package / "meshes" / "tet.stl", TET, TET_FACES)
    write_box_obj(package / "meshes" / "box.obj", (0.02, 0.03, 0.15))
    urdf = package / "urdf" / "toy.urdf"
    urdf.parent.mkdir(parents=True, exist_ok=True)
    urdf.write_text(TOY.replace("{box}", box), encoding="utf-8")
    return urdf


def test_package_uri_found_in_the_package_folder_or_its_parent(tmp_path: Path) -> None:
    toy_arm(tmp_path)
    uri = "package://toyarm/meshes/tet.stl"
    expected = (tmp_path / "toyarm" / "meshes" / "tet.stl").resolve()
    assert resolve_package_uri(uri, (tmp_path,)) == expected
    assert resolve_package_uri(uri, (tmp_path / "toyarm",)) == expected
    assert resolve_package_uri(uri, (tmp_path / "toyarm" / "meshes",)) is None
    assert resolve_package_uri("package://toyarm", (tmp_path,)) is None
    assert resolve_package_uri("package://other/meshes/tet.stl", (tmp_path,)) is None


def test_package_path_from_the_environment() -> None:
    env = {"ROS_PACKAGE_PATH": os.pathsep.join(["/a/b", "", "/c"])}
    assert package_dirs_from_env(env) == (Path("/a/b"), Path("/c"))
    assert package_dirs_from_env({}) == ()


def test_mesh_paths_become_absolute(tmp_path: Path) -> None:
    urdf = toy_arm(tmp_path)
    text = read_urdf(urdf, (tmp_path,))
    assert "package://toyarm" not in text
    # visual meshes and plugins are not the planner's business: left as they are
    assert 'filename="package://elsewhere/link2.dae"' in text
    assert 'filename="libgazebo_ros_control.so"' in text
    assert f'filename="{(tmp_path / "toyarm" / "meshes" / "tet.stl").resolve()}"' in text
    assert f'filename="{(tmp_path / "toyarm" / "meshes" / "box.obj").resolve()}"' in text
    # a relative path is taken from the URDF's folder, a file:// URI as it is
    absolute = tmp_path / "toyarm" / "meshes" / "box.obj"
    urdf = toy_arm(tmp_path, box=f"file://{absolute}")
    assert f'filename="{absolute.resolve()}"' in read_urdf(urdf, (tmp_path,))


def test_missing_package_is_located_at_the_uri(tmp_path: Path) -> None:
    urdf = toy_arm(tmp_path)
    with pytest.raises(SceneError) as info:
        read_urdf(urdf, (tmp_path / "elsewhere",))
    message = str(info.value)
    assert message.startswith(f"{urdf}:7:33: ")
    assert "mesh 'package://toyarm/meshes/tet.stl' not found" in message
    assert "elsewhere" in message
    with pytest.raises(SceneError, match="none given"):
        read_urdf(urdf)


def test_missing_relative_mesh_is_located(tmp_path: Path) -> None:
    urdf = toy_arm(tmp_path, box="meshes/nothing.obj")
    with pytest.raises(SceneError, match=r"toy\.urdf:11:42: mesh 'meshes/nothing\.obj' not found"):
        read_urdf(urdf, (tmp_path,))


def test_malformed_xml_is_located(tmp_path: Path) -> None:
    urdf = tmp_path / "bad.urdf"
    urdf.write_text('<robot name="r">\n  <link name="a">\n</robot>\n', encoding="utf-8")
    with pytest.raises(SceneError, match=r"bad\.urdf:3:\d+: not a well-formed robot description"):
        read_urdf(urdf)
    urdf.write_text("<sdf/>\n", encoding="utf-8")
    with pytest.raises(SceneError, match=r"bad\.urdf:1:1: expected a <robot> root element"):
        read_urdf(urdf)


def test_a_description_pinocchio_rejects_is_located(tmp_path: Path) -> None:
    urdf = tmp_path / "orphan.urdf"
    urdf.write_text(
        '<robot name="r"><link name="a"/><joint name="j" type="fixed">'
        '<parent link="a"/><child link="missing"/></joint></robot>',
        encoding="utf-8",
    )
    with pytest.raises(SceneError, match=r"orphan\.urdf:1:1: the robot description does not load"):
        PinRobot.load(urdf)


def test_meshes_load_as_coal_meshes_with_their_scale(tmp_path: Path) -> None:
    robot = PinRobot.load(toy_arm(tmp_path), (tmp_path,))
    kinds = {str(o.name): type(o.geometry).__name__ for o in robot.geometry.geometryObjects}
    assert kinds == {"base_0": "Box", "link1_0": "BVHModelOBBRSS", "link2_0": "BVHModelOBBRSS"}
    tet = next(o for o in robot.geometry.geometryObjects if o.name == "link1_0").geometry
    np.testing.assert_allclose(np.asarray(tet.vertices()).max(axis=0), [0.2, 0.2, 0.2])


def test_mesh_primitives_are_their_bounding_boxes(tmp_path: Path) -> None:
    prims = {p.name: p for p in arm_primitives(toy_arm(tmp_path), (tmp_path,))}
    tet, box = prims["link1_0"], prims["link2_0"]
    assert tet.kind == box.kind == "box"
    # the tetrahedron (scaled to 0.2 m) spans [0, 0.2]^3 of its frame, 0.1 m above the joint
    np.testing.assert_allclose(tet.half, (0.1, 0.1, 0.1), atol=1e-12)
    np.testing.assert_allclose(tet.T_joint_shape[:3, 3], (0.1, 0.1, 0.2), atol=1e-12)
    np.testing.assert_allclose(box.half, (0.02, 0.03, 0.15), atol=1e-12)
    np.testing.assert_allclose(box.T_joint_shape, np.eye(4), atol=1e-12)
    assert (tet.joint, box.joint) == (1, 2)


def test_an_unsupported_shape_names_itself(tmp_path: Path) -> None:
    urdf = tmp_path / "capsule.urdf"
    urdf.write_text(
        '<robot name="r"><link name="a"><collision><geometry><capsule radius="0.1" '
        'length="0.2"/></geometry></collision><visual><geometry><capsule radius="0.1" '
        'length="0.2"/></geometry></visual></link></robot>',
        encoding="utf-8",
    )
    with pytest.raises(SceneError, match=r"capsule\.urdf:1:54: a collision shape 'capsule'"):
        PinRobot.load(urdf)


def _ur5e_with_mesh_wrist(root: Path, size: float) -> Path:
    """The shipped scene with the wrist_3 link's collision shape a tetrahedron mesh of side
    ``size`` [m] given by a ``package://`` URI; returns the scene file."""
    write_stl(root / "cellmeshes" / "meshes" / "tet.stl", TET * size, TET_FACES)
    text = domain_path("robots/ur5e_2f85.urdf").read_text(encoding="utf-8")
    old = '<geometry><cylinder radius="0.038" length="0.05"/></geometry>'
    assert text.count(old) == 1
    new = '<geometry><mesh filename="package://cellmeshes/meshes/tet.stl"/></geometry>'
    (root / "robot.urdf").write_text(text.replace(old, new), encoding="utf-8")
    scene = default_scene_path().read_text(encoding="utf-8")
    scene = scene.replace("robot: ../robots/ur5e_2f85.urdf", "packages: [.]\nrobot: robot.urdf")
    path = root / "scene.yaml"
    path.write_text(scene, encoding="utf-8")
    return path


def test_the_collision_model_checks_the_exact_mesh(tmp_path: Path) -> None:
    scene = load_scene(_ur5e_with_mesh_wrist(tmp_path, 0.3))
    arms = build_dual_arm(scene)
    names = [str(o.name) for o in arms.arm_geometry.geometryObjects]
    mesh = "left_wrist_3_link_0"
    assert type(arms.arm_geometry.geometryObjects[names.index(mesh)].geometry).__name__.startswith(
        "BVHModel"
    )
    q = scene.home
    empty = build_scene_geometry(arms, scene.table.size, {}, {}, [])
    T_world_mesh = link_poses(arms, empty, q)[mesh]

    def hits(point: tuple[float, float, float], side: float) -> bool:
        T = T_world_mesh @ translation(*point)
        geometry = build_scene_geometry(
            arms, scene.table.size, {"o": (T, (side,) * 3)}, {}, [(mesh, "object:o")]
        )
        return bool(colliding_pairs(arms, geometry, q))

    assert hits((0.05, 0.05, 0.05), 0.12)  # across the tetrahedron's faces
    assert not hits((0.2, 0.2, 0.2), 0.02)  # inside its bounding box, outside the tetrahedron
    assert not hits((1.0, 1.0, 1.0), 0.02)


def test_scene_packages_and_the_environment_resolve_the_robot(tmp_path: Path) -> None:
    path = _ur5e_with_mesh_wrist(tmp_path, 0.1)
    scene = load_scene(path, environ={})
    assert scene.package_dirs == (tmp_path / ".",)
    # without the scene's packages the environment's package path serves
    text = path.read_text(encoding="utf-8").replace("packages: [.]\n", "")
    path.write_text(text, encoding="utf-8")
    with pytest.raises(SceneError, match=r"robot\.urdf:\d+:\d+: mesh 'package://cellmeshes"):
        load_scene(path, environ={})
    scene = load_scene(path, environ={"ROS_PACKAGE_PATH": str(tmp_path)})
    assert scene.package_dirs == (tmp_path,)
    # the robot itself may be a package:// URI
    (tmp_path / "cellmeshes" / "robot.urdf").write_bytes((tmp_path / "robot.urdf").read_bytes())
    path.write_text(
        text.replace("robot: robot.urdf", "robot: package://cellmeshes/robot.urdf"), "utf-8"
    )
    scene = load_scene(path, environ={"ROS_PACKAGE_PATH": str(tmp_path)})
    assert scene.robot_urdf == (tmp_path / "cellmeshes" / "robot.urdf").resolve()
    with pytest.raises(SceneError, match=r"scene\.yaml:\d+:\d+: robot: expected a robot desc"):
        load_scene(path, environ={})


def test_missing_package_directory_is_located(tmp_path: Path) -> None:
    path = _ur5e_with_mesh_wrist(tmp_path, 0.1)
    path.write_text(path.read_text("utf-8").replace("packages: [.]", "packages: [nope]"), "utf-8")
    with pytest.raises(SceneError, match=r"scene\.yaml:4:\d+: packages\[0\]: expected a package"):
        load_scene(path)


def test_the_example_robot_data_share_may_be_named_by_the_environment(tmp_path: Path) -> None:
    from sdar_tamp.world.urdf import example_robot_data_share

    (tmp_path / "example-robot-data" / "robots").mkdir(parents=True)
    assert example_robot_data_share({"EXAMPLE_ROBOT_DATA_SHARE": str(tmp_path)}) == tmp_path
    # a named folder without the package: the installed one, or None where it is not
    missing = {"EXAMPLE_ROBOT_DATA_SHARE": str(tmp_path / "x")}
    assert example_robot_data_share(missing) == example_robot_data_share({})
