"""A UR3 cell from ``example-robot-data`` as it ships (not a shipped robot): the closed form
is found from its URDF with the UR3's lengths, both arms together grasp every point of the
cell's workspace, and instances generated in the cell load with it. Skips without
``example-robot-data`` (an optional extra)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.world.urdf import example_robot_data_share

SHARE = example_robot_data_share()
pytestmark = pytest.mark.skipif(SHARE is None, reason="example-robot-data is not installed")
DATA = Path(__file__).with_name("data")


def test_the_ur3_closed_form_comes_from_the_urdf() -> None:
    from sdar_tamp.world.kinematics import ArmKinematics
    from sdar_tamp.world.scene import load_scene

    assert SHARE is not None
    scene = load_scene(DATA / "maker_ur3_pair.yaml", environ={"ROS_PACKAGE_PATH": str(SHARE)})
    assert scene.arms[0].urdf.name == "ur3_robot.urdf"
    kin = ArmKinematics.from_scene(scene, "right")
    assert kin.closed_form and kin.params is not None
    assert kin.params.a2 == pytest.approx(-0.24365)
    assert kin.params.a3 == pytest.approx(-0.21325)
    rng = np.random.default_rng(0)
    lower = np.array(scene.arms[1].lower)
    upper = np.array(scene.arms[1].upper)
    q = rng.uniform(np.maximum(lower, -np.pi), np.minimum(upper, np.pi), size=(20, 6))
    poses = np.stack([kin.fk_tcp(row) for row in q])
    solved = kin.ik_tcp(poses)
    assert solved.valid.any(axis=-1).all()  # every pose reached by some branch


def test_the_ur3_cell_reaches_its_workspace_and_its_instances_load() -> None:
    from sdar_tamp.world.cell_reach import uncovered_points, unreached_points
    from sdar_tamp.world.instance import load_instance
    from sdar_tamp.world.scene import load_scene

    assert SHARE is not None
    scene = load_scene(DATA / "maker_ur3_pair.yaml", environ={"ROS_PACKAGE_PATH": str(SHARE)})
    missed = unreached_points(scene, 0.05)
    assert set(missed) == {"left", "right"}
    assert len(uncovered_points(missed)) == 0  # every point grasped by one arm at least
    assert all(0 < len(m) < 63 for m in missed.values())  # the far corners: one arm only
    for name in ("R4", "S6", "D6", "M6"):
        instance = load_instance(DATA / "maker_ur3" / f"{name}.yaml")
        assert instance.name == name and len(instance.objects) >= 4
