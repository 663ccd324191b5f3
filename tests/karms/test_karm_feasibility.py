"""The infeasibility checker attributes contacts to the arm that owns each shape, also when
one arm's name is a prefix of another's (``s`` beside ``s_e``)."""

from __future__ import annotations

import dataclasses

from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import pose_xyz_yaw
from streams.context import WorldContext
from streams.feasibility import PLANNER_MARGIN, _Candidate, _Checker

SIZE = (0.06, 0.06, 0.06)


def _renamed(scene: Scene) -> Scene:
    names = {"south": "s", "north": "n", "west": "w", "east": "s_e"}
    arms = tuple(dataclasses.replace(a, name=names[a.name]) for a in scene.arms)
    return dataclasses.replace(scene, arms=arms)


def test_contacts_of_an_arm_named_like_a_prefix_are_not_the_other_arms(
    cells: dict[int, Scene],
) -> None:
    """An object sits in the gripper of the waiting arm ``s_e``; arm ``s`` at its home touches
    nothing: the contact of ``s_e`` is not counted as ``s``'s, but ``s_e``'s own check sees
    it."""
    ctx = WorldContext.load(_renamed(cells[4]))
    tcp = ctx.kinematics["s_e"].fk_tcp(ctx.home("s_e"))
    x, y, z = (float(v) for v in tcp[:3, 3])
    boxes = {"stuck": ObjectBox(pose_xyz_yaw(x, y, z, 0.0), SIZE)}
    checker = _Checker(ctx, boxes, {"stuck": ()}, 0.05, PLANNER_MARGIN)
    checker.rest(["stuck"])
    q_s, q_e = ctx.home("s"), ctx.home("s_e")
    assert checker.world.in_collision(ctx.layout.join(checker.home))  # the set-up holds
    assert checker.hits("other", _Candidate("s", q_s, q_s), q_s) == set()
    assert checker.hits("other", _Candidate("s_e", q_e, q_e), q_e) == {"stuck"}
