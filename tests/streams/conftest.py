"""Shared fixtures of the stream tests: the mixed instance M1 and its objects at their starts
(the world context and the motion planner come from tests/conftest.py)."""

from __future__ import annotations

import pytest

from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.instance import Instance, load_instance
from sdar_tamp.world.scene import domain_path
from sdar_tamp.world.transforms import pose_xyz_yaw


@pytest.fixture(scope="session")
def instance() -> Instance:
    return load_instance(domain_path("suites/paper/M1.yaml"))


@pytest.fixture(scope="session")
def objects(instance: Instance) -> dict[str, ObjectBox]:
    return {
        o.name: ObjectBox(pose_xyz_yaw(o.start.x, o.start.y, o.size[2] / 2, o.start.yaw), o.size)
        for o in instance.objects
    }
