"""Makers' robot descriptions from ``example-robot-data`` (BSD-3-Clause; optional: about
130 MB to download, 415 MB installed). The tests skip when it is not installed; the
environment variable ``EXAMPLE_ROBOT_DATA_SHARE`` may name its ``share`` directory."""

from __future__ import annotations

import os
import site
import sys
from pathlib import Path

import pytest

from sdar_tamp.world._pin import PinRobot
from sdar_tamp.world.errors import SceneError
from streams._pin_geometry import arm_primitives


def _share() -> Path | None:
    given = os.environ.get("EXAMPLE_ROBOT_DATA_SHARE")
    roots = [Path(given)] if given else []
    for prefix in [*site.getsitepackages(), sys.prefix]:
        roots += [Path(prefix) / "cmeel.prefix" / "share", Path(prefix) / "share"]
    return next((r for r in roots if (r / "example-robot-data" / "robots").is_dir()), None)


SHARE = _share()
pytestmark = pytest.mark.skipif(SHARE is None, reason="example-robot-data is not installed")

ARMS = {
    "ur_description/urdf/ur10_robot.urdf": 6,
    "ur_description/urdf/ur5_robot.urdf": 6,
    "panda_description/urdf/panda.urdf": 9,
    "xarm_description/urdf/xarm7.urdf": 7,
}


@pytest.mark.parametrize("relative", sorted(ARMS))
def test_maker_arms_load_with_their_meshes(relative: str) -> None:
    assert SHARE is not None
    robots = SHARE / "example-robot-data" / "robots"
    urdf = robots / relative
    robot = PinRobot.load(urdf, (robots, SHARE))
    assert robot.nq == ARMS[relative]
    kinds = {type(o.geometry).__name__ for o in robot.geometry.geometryObjects}
    assert any(k.startswith("BVHModel") for k in kinds)
    prims = arm_primitives(urdf, (robots, SHARE))
    assert len(prims) == len(robot.geometry.geometryObjects)
    assert all(p.kind == "box" and min(p.half) >= 0.0 for p in prims)


def test_without_package_directories_the_missing_mesh_is_located() -> None:
    assert SHARE is not None
    urdf = SHARE / "example-robot-data" / "robots" / "panda_description" / "urdf" / "panda.urdf"
    with pytest.raises(SceneError, match=r"panda\.urdf:\d+:\d+: mesh 'package://"):
        PinRobot.load(urdf)
