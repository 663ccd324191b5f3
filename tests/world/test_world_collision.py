from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from sdar_tamp.world.collision import CollisionPair, CollisionWorld, ObjectBox
from sdar_tamp.world.errors import ArmLayoutError, CollisionModelError
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.layout import ArmLayout
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import pose_xyz_yaw, top_down_pose

SIZE = (0.08, 0.04, 0.05)
LAYOUT = ArmLayout(("left", "right"), (6, 6))  # the shipped scene's


@pytest.fixture(scope="module")
def kins(scene: Scene) -> dict[str, ArmKinematics]:
    return {a: ArmKinematics.from_scene(scene, a) for a in scene.arm_names}


@pytest.fixture()
def world(scene: Scene) -> CollisionWorld:
    return CollisionWorld(scene)


def _reach(kin: ArmKinematics, x: float, y: float, z: float, yaw: float = 0.0) -> np.ndarray:
    q, ok = kin.ik_tcp(top_down_pose(x, y, z, yaw)[None]).closest(np.array(kin.spec.home))
    assert ok[0]
    return q[0]


def _q(q_left: np.ndarray, q_right: np.ndarray) -> np.ndarray:
    """Both arms' joints as one configuration, in the scene's layout."""
    return LAYOUT.join({"left": q_left, "right": q_right})


def _box(x: float, y: float, yaw: float = 0.0) -> ObjectBox:
    return ObjectBox(pose_xyz_yaw(x, y, SIZE[2] / 2, yaw), SIZE)


def test_home_configurations_are_free(world: CollisionWorld, scene: Scene) -> None:
    home = np.array(scene.arms[0].home)
    assert not world.in_collision(_q(home, home))
    assert world.report(_q(home, home)) == ()
    assert world.min_distance(_q(home, home)).distance > 0.0


def test_arms_driven_into_each_other_collide(world: CollisionWorld, kins: dict) -> None:
    q_l = _reach(kins["left"], 0.0, 0.0, 0.15)
    q_r = _reach(kins["right"], 0.0, 0.0, 0.15)
    home = np.array(kins["right"].spec.home)
    assert not world.in_collision(_q(q_l, home))
    assert world.in_collision(_q(q_l, q_r))
    pairs = world.report(_q(q_l, q_r))
    assert any(p.first.startswith("left_") and p.second.startswith("right_") for p in pairs)
    assert world.min_distance(_q(q_l, q_r)).distance < 0.0


def test_arm_into_the_table_collides(world: CollisionWorld, kins: dict) -> None:
    home = np.array(kins["right"].spec.home)
    q_l = _reach(kins["left"], 0.0, 0.0, 0.05)  # fingertips 0.017 m below the TCP: free
    assert not world.in_collision(_q(q_l, home))
    q_l = _reach(kins["left"], 0.0, 0.0, 0.0)
    assert world.in_collision(_q(q_l, home))
    assert any(p.second == "table" for p in world.report(_q(q_l, home)))


def test_object_under_the_gripper_collides_until_held(world: CollisionWorld, kins: dict) -> None:
    world.set_objects({"o0": _box(0.0, 0.1), "o1": _box(-0.1, -0.2)})
    home = np.array(kins["right"].spec.home)
    above = _reach(kins["left"], 0.0, 0.1, 0.2)
    grasp = _reach(kins["left"], 0.0, 0.1, SIZE[2] / 2)  # fingers close along world y
    off = _reach(kins["left"], 0.0, 0.13, SIZE[2] / 2)  # a finger lands in the object
    assert not world.in_collision(_q(above, home))
    assert not world.in_collision(_q(grasp, home))  # open fingers straddle the 0.04 m side
    assert world.in_collision(_q(off, home))
    pairs = {(p.first, p.second) for p in world.report(_q(off, home))}
    assert ("left_gripper_left_finger_0", "object:o0") in pairs
    # turned by 90 deg the 0.08 m side would lie between the fingers: wider than the 0.060 m
    # pre-grasp opening, so a finger lands in the object
    across = _reach(kins["left"], 0.0, 0.1, SIZE[2] / 2, yaw=np.pi / 2)
    assert world.in_collision(_q(across, home))
    world.attach("left", "o0", grasp)
    assert world.held_by("left") == "o0"
    assert not world.in_collision(_q(grasp, home))  # the held object never hits its own gripper
    lifted = _reach(kins["left"], 0.0, 0.1, 0.2)
    assert not world.in_collision(_q(lifted, home))
    assert world.in_collision(_q(off, home)) is False  # held: moves with the gripper
    placed = world.detach("left", grasp)
    np.testing.assert_allclose(placed.T_world_obj, _box(0.0, 0.1).T_world_obj, atol=1e-9)
    assert world.in_collision(_q(off, home))


def test_held_object_against_table_objects_and_other_held(
    world: CollisionWorld, kins: dict
) -> None:
    world.set_objects({"a": _box(-0.1, 0.0), "b": _box(0.1, 0.0), "c": _box(0.0, 0.2)})
    q_l = _reach(kins["left"], -0.1, 0.0, SIZE[2] / 2)
    q_r = _reach(kins["right"], 0.1, 0.0, SIZE[2] / 2)
    world.attach("left", "a", q_l)
    world.attach("right", "b", q_r)
    assert not world.in_collision(_q(q_l, q_r))
    # held object pushed into the table
    low = _reach(kins["left"], -0.1, 0.0, 0.0)
    assert ("held:a", "table") in {(p.first, p.second) for p in world.report(_q(low, q_r))}
    # held object lowered onto a resting one
    onto = _reach(kins["left"], 0.0, 0.2, SIZE[2] / 2 + 0.03)
    assert any({p.first, p.second} == {"held:a", "object:c"} for p in world.report(_q(onto, q_r)))
    # both held objects brought together high above the table
    q_l2 = _reach(kins["left"], -0.03, 0.0, 0.35)
    q_r2 = _reach(kins["right"], 0.03, 0.0, 0.35)
    assert any({p.first, p.second} == {"held:a", "held:b"} for p in world.report(_q(q_l2, q_r2)))


def test_bad_requests_raise(world: CollisionWorld) -> None:
    world.set_objects({"a": _box(0.0, 0.0)})
    with pytest.raises(CollisionModelError, match="no resting object"):
        world.attach("left", "zz")
    with pytest.raises(CollisionModelError, match="unknown arm"):
        world.attach("middle", "a")
    with pytest.raises(CollisionModelError, match="holds nothing"):
        world.detach("left")
    world.attach("left", "a")
    with pytest.raises(CollisionModelError, match="already holds"):
        world.attach("left", "a")
    with pytest.raises(CollisionModelError, match="held"):
        world.set_objects({"a": _box(0.0, 0.0)})


def test_configuration_is_stored(world: CollisionWorld, kins: dict) -> None:
    q_l = _reach(kins["left"], 0.0, 0.0, 0.15)
    q_r = _reach(kins["right"], 0.0, 0.0, 0.15)
    world.set_configuration(_q(q_l, q_r))
    assert world.in_collision()
    np.testing.assert_allclose(world.layout.part(world.configuration, "left"), q_l)
    np.testing.assert_allclose(world.configuration, _q(q_l, q_r))
    np.testing.assert_allclose(world.tool0_pose("left"), kins["left"].fk_tool0(q_l), atol=1e-12)


def test_coal_adapter_distance_between_boxes() -> None:
    from sdar_tamp.world._coal import box, shape_distance

    a, b = box(SIZE), box(SIZE)
    d = shape_distance(a, _box(0.0, 0.0).T_world_obj, b, _box(0.18, 0.0).T_world_obj)
    assert d == pytest.approx(0.10, abs=1e-9)
    d = shape_distance(a, _box(0.0, 0.0).T_world_obj, b, _box(0.07, 0.0).T_world_obj)
    assert d == pytest.approx(-0.01, abs=1e-6)


def test_configuration_of_the_wrong_shape_is_refused(world: CollisionWorld, scene: Scene) -> None:
    assert world.layout == scene.layout == LAYOUT
    home = np.array(scene.arms[0].home)
    with pytest.raises(
        ArmLayoutError, match=r"expected shape \(12,\) for arms \['left', 'right'\]"
    ):
        world.in_collision(home)  # one arm only
    with pytest.raises(ArmLayoutError, match="got \\(13,\\)"):
        world.set_configuration(np.zeros(13))
    np.testing.assert_allclose(world.configuration, scene.home)  # unchanged


def test_an_arrangement_seen_before_reuses_its_geometry_and_answers_alike(
    kins: dict, scene: Scene, monkeypatch: pytest.MonkeyPatch
) -> None:
    import sdar_tamp.world.collision_model as cm

    keep = 16
    world = CollisionWorld(scene, keep=keep)
    builds: list[int] = []
    build = cm.build_scene_geometry
    monkeypatch.setattr(cm, "build_scene_geometry", lambda *a: builds.append(1) or build(*a))
    home = np.array(kins["right"].spec.home)
    grasp = _reach(kins["left"], 0.0, 0.1, SIZE[2] / 2)
    off = _reach(kins["left"], 0.0, 0.13, SIZE[2] / 2)
    first = {"o0": _box(0.0, 0.1), "o1": _box(-0.1, -0.2)}
    moved = {"o0": _box(0.1, 0.1), "o1": _box(-0.1, -0.2)}
    answers = []
    for objects in (first, moved, first, moved):
        world.set_objects(objects)
        answers.append((world.in_collision(_q(off, home)), world.report(_q(off, home))))
    assert len(builds) == 2  # one per arrangement
    assert answers[0] == answers[2] and answers[1] == answers[3]
    assert answers[0][0] and not answers[1][0]
    # holding an object is another arrangement; the pose it is put down at is computed
    # through the tool (equal within rounding, not bit for bit): compared exactly, a third one
    world.set_objects(first)
    world.attach("left", "o0", grasp)
    assert not world.in_collision(_q(off, home))
    world.detach("left", grasp)
    assert world.in_collision(_q(off, home))
    assert len(builds) == 4
    # the answers match a fresh world's
    fresh = CollisionWorld(scene)
    fresh.set_objects(first)
    assert fresh.report(_q(off, home)) == world.report(_q(off, home))
    # a bounded cache: far more arrangements than it keeps, then the first one is rebuilt
    for k in range(keep + 1):
        world.set_objects({"o0": _box(0.0, -0.1 + 0.001 * k)})
        world.in_collision(_q(off, home))
    count = len(builds)
    world.set_objects(first)
    world.in_collision(_q(off, home))
    assert len(builds) == count + 1
    # built afresh, nothing kept: every change of arrangement is a build
    plain = CollisionWorld(scene, incremental=False)
    before = len(builds)
    for objects in (first, moved, first):
        plain.set_objects(objects)
        plain.in_collision(_q(off, home))
    assert len(builds) == before + 3
    with pytest.raises(CollisionModelError, match="keep: expected a number of geometries >= 0"):
        CollisionWorld(scene, keep=-1)


def test_worlds_of_one_scene_share_the_arm_model_but_not_its_data(
    scene: Scene, kins: dict[str, ArmKinematics]
) -> None:
    first, second = CollisionWorld(scene), CollisionWorld(scene)
    assert first._arms.model is second._arms.model
    assert first._arms.data is not second._arms.data
    q = _q(_reach(kins["left"], 0.0, 0.13, SIZE[2] / 2), np.array(scene.arm("right").home))
    first.set_objects({"o": _box(0.0, 0.1)})  # a finger lands in the object
    # one world's queries (which write its pinocchio data) leave the other's answers alone
    assert first.in_collision(q)
    assert not second.in_collision(q)
    assert first.in_collision(q)


def test_pair_names_follow_the_pairs_activated(scene: Scene) -> None:
    world = CollisionWorld(scene, incremental=False)
    world.set_objects({"o": _box(-0.2, 0.0), "p": _box(0.2, 0.1)})
    world.in_collision()
    names = world._geometry.pair_names  # type: ignore[union-attr]
    assert set(names) == set(world._pairs())
    assert len(names) == len(world._pairs())


def test_pair_names_are_aligned_with_the_geometry_pairs(scene: Scene, kins: dict) -> None:
    """``pair_names[k]`` names the shapes of the ``k``-th pair of the geometry (the index
    :func:`colliding_pairs` reports), each pair oriented as :meth:`_pairs` lists it."""
    world = CollisionWorld(scene, arm_margin=0.002, incremental=False)
    world.set_objects({"o": _box(-0.2, 0.0), "p": _box(0.2, 0.1)})
    world.attach("left", "o")
    world.in_collision()
    geometry = world._geometry  # type: ignore[union-attr]
    assert geometry is not None
    objects = geometry.geometry.geometryObjects
    for k, pair in enumerate(geometry.geometry.collisionPairs):
        shapes = {str(objects[pair.first].name), str(objects[pair.second].name)}
        assert set(geometry.pair_names[k]) == shapes
    assert set(geometry.pair_names) == set(world._pairs())
    margins = [r.security_margin for r in geometry.data.collisionRequests]
    for (a, b), margin in zip(geometry.pair_names, margins, strict=True):
        two_arms = {a.split("_")[0], b.split("_")[0]} == {"left", "right"}
        assert margin == (0.002 if two_arms else 0.0), (a, b)


def test_base_pose_is_a_copy(scene: Scene) -> None:
    arm = scene.arms[0]
    T = arm.T_world_base
    T[:3, 3] += 1.0
    assert not np.allclose(arm.T_world_base, T)


def _one_mm_apart(gap: Callable[[float], float], lo: float, hi: float) -> float:
    """A value in ``[lo, hi]`` where ``gap`` (negative at ``lo``, positive at ``hi``) is 1 mm,
    by bisection."""
    assert gap(lo) < 0.0 < gap(hi)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if gap(mid) < 0.001 else (lo, mid)
    return hi


def test_an_arm_margin_keeps_the_two_arms_apart_only(scene: Scene, kins: dict) -> None:
    """Two grippers 1 mm apart: free in the exact world, colliding with a 2 mm arm margin;
    the margin leaves the other pairs alone (a finger 1 mm above the table stays free)."""
    plain, strict = CollisionWorld(scene), CollisionWorld(scene, arm_margin=0.002)
    q_l = _reach(kins["left"], -0.05, 0.0, 0.15)

    def arms(x: float) -> np.ndarray:
        return _q(q_l, _reach(kins["right"], x, 0.0, 0.15))

    q = arms(_one_mm_apart(lambda x: plain.min_distance(arms(x)).distance, -0.05, 0.25))
    assert 0.001 <= plain.min_distance(q).distance < 0.0012
    assert not plain.in_collision(q) and strict.in_collision(q)
    assert any(p.first.startswith("left_") and p.second.startswith("right_")
               for p in strict.report(q))  # fmt: skip
    home = np.array(kins["right"].spec.home)

    def lowered(z: float) -> np.ndarray:
        return _q(_reach(kins["left"], -0.05, 0.0, z), home)

    q_t = lowered(_one_mm_apart(lambda z: plain.min_distance(lowered(z)).distance, 0.0, 0.3))
    assert plain.min_distance(q_t).pair == CollisionPair("left_gripper_left_finger_0", "table")
    assert not strict.in_collision(q_t)


@pytest.mark.parametrize("margin", [-0.001, 0.05, float("nan")])
def test_a_bad_arm_margin_is_refused(scene: Scene, margin: float) -> None:
    with pytest.raises(CollisionModelError, match=r"arm_margin: expected a distance in \[0, 0"):
        CollisionWorld(scene, arm_margin=margin)
