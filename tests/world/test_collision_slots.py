"""A world's geometry updated in place answers every query as a geometry built afresh."""

from __future__ import annotations

import numpy as np
import pytest

import sdar_tamp.world.collision_model as cm
from sdar_tamp.world.collision import CollisionWorld, ObjectBox
from sdar_tamp.world.collision_slots import SlotGeometry
from sdar_tamp.world.scene import Scene, domain_path, load_scene
from sdar_tamp.world.transforms import pose_xyz_yaw

SIZE = (0.08, 0.04, 0.05)


@pytest.fixture(scope="module")
def four() -> Scene:
    return load_scene(domain_path("cells/ur5e_table_4arm.yaml"))


def _box(rng: np.random.Generator, size: tuple[float, float, float] = SIZE) -> ObjectBox:
    x, y = rng.uniform(-0.45, 0.45), rng.uniform(-0.35, 0.35)
    return ObjectBox(pose_xyz_yaw(x, y, size[2] / 2, rng.uniform(-3, 3)), size)


def _random_q(scene: Scene, rng: np.random.Generator) -> np.ndarray:
    home = scene.home
    return home + rng.uniform(-0.9, 0.9, home.shape)


def _same_answers(a: CollisionWorld, b: CollisionWorld, qs: list[np.ndarray]) -> None:
    for q in qs:
        assert a.in_collision(q) == b.in_collision(q)
        assert set(a.report(q)) == set(b.report(q))
        da, db = a.min_distance(q), b.min_distance(q)
        assert da.distance == pytest.approx(db.distance, abs=1e-6)
        ca, cb = a.arm_clearances(q), b.arm_clearances(q)
        assert ca.keys() == cb.keys()
        for key in ca:
            assert ca[key].distance == pytest.approx(cb[key].distance, abs=1e-6)


@pytest.mark.parametrize("arm_margin", [0.0, 0.004])
def test_a_sequence_of_arrangements_answers_as_fresh_geometries(
    four: Scene, arm_margin: float
) -> None:
    """Objects moved, removed, added back, held by one arm then by two, put down elsewhere:
    after each change the world updated in place gives a fresh world's answers (collisions,
    colliding pairs, distances, arm clearances) at random configurations, and checks the
    same pairs, named alike."""
    rng = np.random.default_rng(3)
    slots = CollisionWorld(four, arm_margin=arm_margin)
    names = [f"o{i}" for i in range(8)]
    objects = {n: _box(rng) for n in names}
    qs = [_random_q(four, rng) for _ in range(12)] + [four.home]
    arms = four.arm_names
    for step in range(10):
        fresh = CollisionWorld(four, arm_margin=arm_margin, incremental=False)
        for arm in arms:
            if slots.held_by(arm) is not None:
                slots.detach(arm)
        objects = {n: _box(rng) if rng.random() < 0.3 else b for n, b in objects.items()}
        kept = {n: b for n, b in objects.items() if step % 3 != 1 or n != "o2"}
        slots.set_objects(kept)
        fresh.set_objects(kept)
        for arm, name in list(zip(arms, ["o0", "o5"], strict=False))[: step % 3]:
            q_arm = four.layout.part(qs[step], arm)
            slots.attach(arm, name, q_arm)
            fresh.attach(arm, name, q_arm)
        _same_answers(slots, fresh, qs)
        assert slots._slots is not None
        assert sorted(slots._slots.pair_names) == sorted(fresh._pairs())
    assert slots._slots is not None
    assert set(slots._slots.sizes) == set(names)  # one geometry all along


def test_the_geometry_is_built_once_per_object_set(
    four: Scene, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Moving, holding and removing known objects builds nothing; a new object or a known
    one of another size builds the geometry again, for the objects seen so far."""
    built: list[SlotGeometry] = []
    init = SlotGeometry.__init__

    def counted(self: SlotGeometry, *args: object, **kwargs: object) -> None:
        built.append(self)
        init(self, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(SlotGeometry, "__init__", counted)
    monkeypatch.setattr(cm, "build_scene_geometry", None)  # never built afresh
    rng = np.random.default_rng(5)
    world = CollisionWorld(four)
    world.set_objects({"a": _box(rng), "b": _box(rng)})
    world.in_collision()
    world.set_object("a", _box(rng))
    world.attach(four.arm_names[0], "b")
    world.in_collision()
    world.detach(four.arm_names[0])
    world.remove_object("a")
    world.in_collision()
    assert len(built) == 1
    world.set_object("c", _box(rng))
    world.in_collision()
    assert len(built) == 2 and set(built[-1].sizes) == {"a", "b", "c"}
    world.set_objects({"a": _box(rng)})  # back: no build
    world.in_collision()
    assert len(built) == 2
    world.set_object("c", _box(rng, (0.05, 0.05, 0.05)))
    world.in_collision()
    assert len(built) == 3


def test_an_empty_table_and_a_removed_object_check_no_object_pair(four: Scene) -> None:
    rng = np.random.default_rng(1)
    world = CollisionWorld(four)
    world.set_objects({"a": _box(rng)})
    world.in_collision()
    world.set_objects({})
    assert not world.in_collision(four.home)
    assert world.report(four.home) == ()
    assert world._slots is not None
    assert not any("a" in name.split(":")[-1] for pair in world._slots.pair_names
                   for name in pair if ":" in name)  # fmt: skip


def test_two_arm_answers_match_a_fresh_world_at_a_grasp() -> None:
    """The shipped two-arm cell: a finger in a resting object, then the object held."""
    scene = load_scene()
    rng = np.random.default_rng(11)
    objects = {f"o{i}": _box(rng) for i in range(5)}
    qs = [_random_q(scene, rng) for _ in range(20)]
    slots, fresh = CollisionWorld(scene), CollisionWorld(scene, incremental=False)
    for world in (slots, fresh):
        world.set_objects(objects)
    _same_answers(slots, fresh, qs)
    for world in (slots, fresh):
        world.attach("left", "o1", scene.layout.part(qs[0], "left"))
    _same_answers(slots, fresh, qs)
