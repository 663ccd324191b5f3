"""A two-arm cell of 7-DoF arms (the test URDF ``tests/data/arm7.urdf``, the kinematics of a
Franka Panda) built in code from the shipped scene: table, workspace and object size kept,
arms facing each other across the table."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.world.scene import ArmSpec, Scene, load_scene
from streams.context import WorldContext

ARM7_URDF = Path(__file__).resolve().parents[1] / "data" / "arm7.urdf"
#: Franka's datasheet limits [rad], [rad/s].
LOWER = (-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973)
UPPER = (2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973)
VELOCITY = (2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61)
HOME = (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785)


def seven_dof_scene() -> Scene:
    base = load_scene()
    gripper = replace(base.arms[0].gripper, max_opening=0.07, tcp_offset=0.1034)

    def arm(name: str, x: float, yaw: float) -> ArmSpec:
        return ArmSpec(
            name=name,
            urdf=ARM7_URDF,
            base_xyz=(x, 0.0, 0.0),
            base_yaw=yaw,
            base_frame="base_link",
            tool_frame="tool0",
            joint_names=tuple(f"joint{i}" for i in range(1, 8)),
            lower=LOWER,
            upper=UPPER,
            velocity_limit=VELOCITY,
            acceleration_limit=(5.0,) * 7,
            home=HOME,
            gripper=gripper,
        )

    return replace(
        base,
        file="seven-dof test cell",
        arms=(arm("left", -0.5, 0.0), arm("right", 0.5, float(np.pi))),
    )


@pytest.fixture(scope="session")
def scene7() -> Scene:
    return seven_dof_scene()


@pytest.fixture(scope="session")
def ctx7(scene7: Scene) -> WorldContext:
    return WorldContext.load(scene7)
