"""The collision model reads each arm's chain from the robot description (7-DoF included)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.collision_model import build_dual_arm
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import pose_xyz_yaw
from streams.context import WorldContext
from tests.kinematics.conftest import ARM7_URDF


def test_seven_links_per_arm(ctx7: WorldContext) -> None:
    model = build_dual_arm(ctx7.scene)
    assert model.model.nq == 14
    links = {s.link_index for s in model.shapes if s.arm == "left"}
    assert links == set(range(8))  # the base, then the links of joints 1..7
    world = ctx7.new_world()
    assert not world.in_collision(ctx7.scene.home)
    home = ctx7.home("left")
    np.testing.assert_allclose(
        world.tool0_pose("left", home), ctx7.kinematics["left"].fk_tool0(home), atol=1e-12
    )


def test_a_held_object_may_touch_its_arms_last_link(ctx7: WorldContext) -> None:
    """A box inside the hand (the last link, joint 7) collides while it rests there, not once
    the arm holds it."""
    world = ctx7.new_world()
    home = ctx7.home("left")
    T = ctx7.kinematics["left"].fk_tool0(home) @ pose_xyz_yaw(0.0, 0.0, 0.03, 0.0)
    world.set_objects({"o": ObjectBox(T, (0.04, 0.04, 0.04))})
    assert world.in_collision(ctx7.scene.home)
    world.attach("left", "o", home)
    assert not world.in_collision(ctx7.scene.home)
    world.detach("left", home)
    world.remove_object("o")
    T6 = ctx7.kinematics["left"].fk(home, "link6") @ pose_xyz_yaw(0.05, 0.0, 0.0, 0.0)
    world.set_objects({"p": ObjectBox(T6, (0.02, 0.02, 0.02))})  # on link 6: not allowed
    world.attach("left", "p", home)
    assert world.in_collision(ctx7.scene.home)
    assert any("link6" in p.first + p.second for p in world.report())


def test_missing_or_unmoved_tool_frames_are_refused(scene7: Scene, tmp_path: Path) -> None:
    text = ARM7_URDF.read_text(encoding="utf-8")
    renamed = tmp_path / "renamed.urdf"
    renamed.write_text(text.replace('"tool0"', '"hand0"'), encoding="utf-8")
    with pytest.raises(
        SceneError, match=r"arm 'left': its robot description renamed\.urdf has no frame 'tool0'"
    ):
        build_dual_arm(_with_urdf(scene7, renamed))
    fixed = tmp_path / "fixed.urdf"
    fixed.write_text(
        text.replace('<parent link="flange"/>\n    <child link="tool0"/>',
                     '<parent link="base_link"/>\n    <child link="tool0"/>'),
        encoding="utf-8",
    )  # fmt: skip
    with pytest.raises(
        SceneError, match="the tool frame 'tool0' is not fixed to the arm's last joint"
    ):
        build_dual_arm(_with_urdf(scene7, fixed))


def _with_urdf(scene: Scene, urdf: Path) -> Scene:
    return replace(scene, arms=tuple(replace(a, urdf=urdf) for a in scene.arms))
