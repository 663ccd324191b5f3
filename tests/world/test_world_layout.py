"""The arm layout: joint slices, DoF, names, splitting and joining, and the errors of a bad one."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from sdar_tamp.errors import SdarError
from sdar_tamp.world import ArmLayout, ArmLayoutError
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.scene import Scene


def test_slices_follow_the_order_and_the_dof_of_the_arms() -> None:
    layout = ArmLayout(("a", "b", "c"), (6, 7, 2))
    assert len(layout) == 3 and layout.dof == 15 and list(layout) == ["a", "b", "c"]
    assert layout.slices == (slice(0, 6), slice(6, 13), slice(13, 15))
    assert layout.slice("b") == layout.slice(1) == slice(6, 13)
    assert layout.index("c") == 2 and "b" in layout and "d" not in layout
    assert [layout.locate(j) for j in (0, 5, 6, 12, 13, 14)] == [
        ("a", 0), ("a", 5), ("b", 0), ("b", 6), ("c", 0), ("c", 1),
    ]  # fmt: skip
    assert ArmLayout.uniform(("l", "r"), 6) == ArmLayout(("l", "r"), (6, 6))


def test_split_and_join_are_inverse_on_vectors_and_paths() -> None:
    layout = ArmLayout(("a", "b", "c"), (2, 3, 1))
    q = np.arange(6.0)
    parts = layout.split(q)
    assert {k: v.tolist() for k, v in parts.items()} == {"a": [0, 1], "b": [2, 3, 4], "c": [5]}
    np.testing.assert_array_equal(layout.join(parts), q)
    np.testing.assert_array_equal(layout.join([parts["a"], parts["b"], parts["c"]]), q)
    path = np.arange(12.0).reshape(2, 6)
    np.testing.assert_array_equal(layout.part(path, "b"), [[2, 3, 4], [8, 9, 10]])
    np.testing.assert_array_equal(layout.join(layout.split(path)), path)
    parts["a"][0] = 99.0  # split copies
    assert q[0] == 0.0
    moved = layout.replace(q, "c", [7.0])
    assert moved.tolist() == [0, 1, 2, 3, 4, 7] and q[5] == 5.0  # replace copies


def test_the_scene_layout_is_its_arms_with_six_joints_each(scene: Scene) -> None:
    layout = scene.layout
    assert layout.names == scene.arm_names == ("left", "right")
    assert layout.dofs == (6, 6) and layout.dof == 12
    home = scene.home
    for arm in scene.arms:
        np.testing.assert_array_equal(layout.part(home, arm.name), arm.home)
        np.testing.assert_array_equal(
            layout.part(scene.joint_array("velocity_limit"), arm.name), arm.velocity_limit
        )
    with pytest.raises(SceneError, match="field must be one of lower, upper"):
        scene.joint_array("home_sweet_home")


def test_a_third_arm_is_only_data(scene: Scene) -> None:
    third = dataclasses.replace(scene.arms[0], name="middle")
    three = dataclasses.replace(scene, arms=(*scene.arms, third))
    assert three.layout.names == ("left", "right", "middle") and three.layout.dof == 18
    assert three.layout.slice("middle") == slice(12, 18)
    np.testing.assert_array_equal(three.home[12:], third.home)


@pytest.mark.parametrize(
    ("names", "dofs", "message"),
    [
        ((), (), "names must hold at least one arm, got none"),
        (("a", "b"), (6,), r"dofs must have one entry per arm \(2\), got 1"),
        (("a", "a"), (6, 6), r"arm names must differ, got \['a'\] twice"),
        (("a", ""), (6, 6), "arm names must be non-empty strings, got ''"),
        (("a", "b"), (6, 0), "the dof of arm 'b' must be an integer >= 1, got 0"),
        (("a",), (2.5,), "the dof of arm 'a' must be an integer >= 1, got 2.5"),
        (("a",), (True,), "the dof of arm 'a' must be an integer >= 1, got True"),
    ],
)
def test_bad_layouts_are_refused(
    names: tuple[str, ...], dofs: tuple[int, ...], message: str
) -> None:
    with pytest.raises(ArmLayoutError, match=message) as info:
        ArmLayout(names, dofs)
    assert isinstance(info.value, SdarError) and isinstance(info.value, ValueError)


def test_bad_requests_name_what_was_expected() -> None:
    layout = ArmLayout(("left", "right"), (6, 6))
    with pytest.raises(
        ArmLayoutError, match=r"unknown arm 'middle'; the layout has \['left', 'right'\]"
    ):
        layout.slice("middle")
    with pytest.raises(ArmLayoutError, match=r"arm index must be in \[0, 1\], got 2"):
        layout.slice(2)
    with pytest.raises(ArmLayoutError, match=r"joint must be in \[0, 11\], got 12"):
        layout.locate(12)
    with pytest.raises(ArmLayoutError, match=r"q: expected shape \(\.\.\., 12\) .*got \(11,\)"):
        layout.split(np.zeros(11))
    with pytest.raises(ArmLayoutError, match=r"q: expected shape \(\.\.\., 12\) .*got \(\)"):
        layout.check(1.0)
    with pytest.raises(ArmLayoutError, match=r"missing \['right'\], unknown \['middle'\]"):
        layout.join({"left": np.zeros(6), "middle": np.zeros(6)})
    with pytest.raises(ArmLayoutError, match=r"expected 2 parts .* got 1"):
        layout.join([np.zeros(12)])
    with pytest.raises(
        ArmLayoutError, match=r"arm 'right' must have shape \(\.\.\., 6\), got \(5,\)"
    ):
        layout.join([np.zeros(6), np.zeros(5)])
