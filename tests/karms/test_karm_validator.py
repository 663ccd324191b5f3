"""The validator on plans of three and four arms: contact checked between every pair of arms
(and their held objects), gripper events of any subset of the arms, objects held per arm; a
four-arm plan whose arms pass close to each other passes, the same plan moved into contact and
an asynchronous plan with one arm shifted in time into another are rejected, naming the arms
and the time."""

from __future__ import annotations

import dataclasses
from itertools import combinations

import numpy as np
import pytest
from karm_cells import build, cell, crossing, instance_of, pick_place, relay, shifted

from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_rules import check_timeline
from sdar_tamp.replay import validate_plan
from sdar_tamp.replay_walk import describe_contacts
from sdar_tamp.schedule import schedule_async
from sdar_tamp.world.collision import CollisionPair, CollisionWorld, ObjectBox
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import pose_xyz_yaw


def _closest(plan: PlanFile, scene: Scene, stride: int = 5) -> dict[tuple[str, str], float]:
    """The smallest distance [m] between every pair of arms over the plan's samples (nothing
    held: the arms' own shapes)."""
    world = CollisionWorld(scene)
    out: dict[tuple[str, str], float] = {}
    for q in plan.q[::stride]:
        for pair, c in world.arm_clearances(q).items():
            out[pair] = min(out.get(pair, np.inf), c.distance)
    return out


def test_every_pair_of_arms_is_checked(cells: dict[int, Scene]) -> None:
    four = CollisionWorld(cells[4])
    pairs = four.arm_clearances(cells[4].home)
    assert list(pairs) == list(combinations(cells[4].arm_names, 2))  # six pairs, scene order
    assert all(c.pair is not None and c.distance > 0.1 for c in pairs.values())
    for (a, b), c in pairs.items():
        assert c.pair is not None
        assert {four.owner(c.pair.first), four.owner(c.pair.second)} == {a, b}
    assert CollisionWorld(cells[1]).arm_clearances(cells[1].home) == {}
    assert four.owner("table") is None and four.owner("east_wrist_3_link_0") == "east"


def test_a_four_arm_plan_whose_arms_pass_close_replays_without_contact(
    cells: dict[int, Scene], instances: dict[int, Instance], plans: dict[int, PlanFile]
) -> None:
    report = validate_plan(instances[4], plans[4], cells[4])
    assert report.ok, report.violation
    closest = _closest(plans[4], cells[4])
    near = [pair for pair, d in closest.items() if d < 0.05]
    assert len(near) >= 5  # every pair of neighbouring arms within 5 cm of each other
    assert min(closest.values()) > 0.0


def test_the_same_plan_moved_into_contact_is_rejected_naming_the_arms_and_the_time() -> None:
    scene = cell(4)
    moves = crossing(4, gap=0.10)  # the south and north objects 6 cm closer
    instance = instance_of("K4", scene, moves)
    plan = build(scene, instance, pick_place(scene, moves))
    assert check_timeline(plan, scene) is None  # limits and dwells hold: only contact fails
    v = validate_plan(instance, plan, scene).violation
    assert v is not None and v.kind == "collision"
    assert v.message.startswith("arms south and north in contact: south_"), v.message
    grasp = max(e.t for e in plan.events if e.type == "grasp")
    release = min(e.t for e in plan.events if e.type == "release")
    assert grasp < v.t < release  # on the way to the goals, before any release
    assert _closest(plan, scene)[("south", "north")] < 0.0


def test_gripper_events_of_any_subset_of_arms_and_objects_held_per_arm(
    cells: dict[int, Scene], instances: dict[int, Instance], plans: dict[int, PlanFile]
) -> None:
    plan, scene, instance = plans[4], cells[4], instances[4]
    releases = [i for i, e in enumerate(plan.events) if e.type == "release"]
    assert len({plan.events[i].t for i in releases}) == 1  # four grippers open at once
    # the south gripper opens on the object the north one holds
    events = list(plan.events)
    south = next(i for i in releases if events[i].arm == "south")
    events[south] = dataclasses.replace(events[south], object="n1")
    v = validate_plan(instance, dataclasses.replace(plan, events=tuple(events)), scene).violation
    assert v is not None and v.kind == "release"
    assert v.message == "south releases n1 but holds s1"
    # three of the four open at once; the south arm lifts; then the west one opens: valid
    phases = pick_place(scene, crossing(4))
    release = phases[6]
    assert isinstance(release, list)
    lift = phases[7]
    assert isinstance(lift, dict)
    phases[6:7] = [
        [e for e in release if e.arm != "west"],
        {"south": lift["south"]},
        [e for e in release if e.arm == "west"],
    ]
    staggered = build(scene, instance, phases)
    opened = {e.arm: e.t for e in staggered.events if e.type == "release"}
    assert opened["south"] == opened["north"] == opened["east"] < opened["west"]
    report = validate_plan(instance, staggered, scene)
    assert report.ok, report.violation
    # the west gripper opening later, its arm lifting before its dwell ends: the dwell rule
    late = tuple(
        dataclasses.replace(e, t=opened["west"] + 0.3) if e.t == opened["west"] else e
        for e in staggered.events
    )
    v = validate_plan(instance, dataclasses.replace(staggered, events=late), scene).violation
    assert v is not None and v.kind == "dwell" and v.t == pytest.approx(opened["west"] + 0.3)
    assert "after the west release of w1" in v.message and "; west shoulder_" in v.message


@pytest.fixture(scope="module")
def relay_plans(cells: dict[int, Scene]) -> tuple[Instance, PlanFile, PlanFile]:
    """The relay on four arms: synchronous, and scheduled asynchronously."""
    scene = cells[4]
    instance, phases = relay(scene)
    plan = build(scene, instance, phases)
    schedule = schedule_async(plan, instance, scene)
    assert schedule.asynchronous
    return instance, plan, schedule.plan


def test_an_asynchronous_four_arm_plan_replays(
    cells: dict[int, Scene], relay_plans: tuple[Instance, PlanFile, PlanFile]
) -> None:
    instance, plan, fast = relay_plans
    assert validate_plan(instance, plan, cells[4]).ok
    assert validate_plan(instance, fast, cells[4]).ok
    assert fast.duration < plan.duration
    assert fast.metrics.execution == "async"


def test_a_mutated_asynchronous_plan_one_arm_shifted_into_another_is_rejected(
    cells: dict[int, Scene], relay_plans: tuple[Instance, PlanFile, PlanFile]
) -> None:
    scene = cells[4]
    instance, _, fast = relay_plans
    at = {(e.arm, e.type): e.t for e in fast.events}
    # the east arm started so much earlier that it reaches the middle as the west one lets go
    ticks = round((at["east", "grasp"] - at["west", "release"]) / (fast.t[1] - fast.t[0]))
    for k in (ticks, ticks // 2):
        mutant = shifted(fast, "east", k)
        assert check_timeline(mutant, scene) is None  # each arm's motion is unchanged
        v = validate_plan(instance, mutant, scene).violation
        assert v is not None and v.kind == "collision", v
        assert v.message.startswith("arms west and east in contact: "), v.message
        # while the west arm is in the middle: after its grasp, before it is home again
        assert at["west", "grasp"] < v.t < at["east", "grasp"]
    # the scheduler started the east arm as early as contact allows: two ticks sooner collide
    v = validate_plan(instance, shifted(fast, "east", 2), scene).violation
    assert v is not None and v.message.startswith("arms west and east in contact: ")


def test_arms_named_by_prefixes_of_each_other_keep_their_shapes(cells: dict[int, Scene]) -> None:
    """An arm named ``s`` beside one named ``s_e``: every shape belongs to its own arm (the
    names of the second's shapes start with ``s_`` too)."""
    scene = cells[4]
    names = {"south": "s", "north": "n", "west": "w", "east": "s_e"}
    renamed = dataclasses.replace(
        scene, arms=tuple(dataclasses.replace(a, name=names[a.name]) for a in scene.arms)
    )
    world = CollisionWorld(renamed, arm_margin=0.01)
    assert world.owner("s_e_wrist_3_link_0") == "s_e" and world.owner("s_wrist_3_link_0") == "s"
    pairs = world.arm_clearances(renamed.home)
    assert len(pairs) == 6 and all(c.distance > 0.1 for c in pairs.values())
    assert not world.in_collision(renamed.home)


def test_contact_messages_name_the_arms_of_held_objects_too(cells: dict[int, Scene]) -> None:
    world = CollisionWorld(cells[4])
    world.set_objects({"o1": ObjectBox(pose_xyz_yaw(0.0, 0.0, 0.025, 0.0), (0.08, 0.04, 0.05))})
    world.attach("west", "o1")
    assert world.owner("held:o1") == "west" and world.owner("object:o1") is None
    pairs = [
        CollisionPair("south_wrist_3_link_0", "object:o2"),
        CollisionPair("held:o1", "east_gripper_base_link_1"),
        CollisionPair("north_wrist_3_link_0", "south_forearm_link_0"),
        CollisionPair("east_wrist_1_link_0", "west_wrist_1_link_0"),
    ]
    assert describe_contacts(pairs, world) == (
        "arms west and east; south and north in contact: south_wrist_3_link_0 with object:o2, "
        "held:o1 with east_gripper_base_link_1, north_wrist_3_link_0 with south_forearm_link_0 ..."
    )
    assert describe_contacts(pairs[:1], world) == "south_wrist_3_link_0 with object:o2"
