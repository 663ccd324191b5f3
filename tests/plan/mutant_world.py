"""Mutants that break the world rules: joint names, swapped arms, arm offsets, objects, the
scene and instance, gripper events, drops in mid-air."""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable, Iterator

import numpy as np

from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D
from sdar_tamp.world.scene import Workspace
from sdar_tamp.world.transforms import FloatArray
from tests.plan.mutant_base import (
    ARMS,
    Base,
    Mutant,
    insert_still,
    rest_junctions,
    with_events,
    with_q,
)


def _joint_names(b: Base) -> Iterator[Mutant]:
    plan = b.plan
    expect = frozenset({"scene"})
    for i, arm in enumerate(plan.arms):
        other = plan.arms[1 - i]
        names = list(arm.joints)
        variants: dict[str, list[str]] = {
            "reversed": names[::-1],
            "upper case": [n.upper() for n in names],
        }
        for k in range(6):
            if k < 5:
                swapped = list(names)
                swapped[k], swapped[k + 1] = swapped[k + 1], swapped[k]
                variants[f"swap {k}-{k + 1}"] = swapped
            for label, wrong in (
                ("other arm's", other.joints[k]),
                ("no prefix", names[k].split("_", 1)[1]),
                ("renamed", names[k].replace("_joint", "_link")),
            ):
                changed = list(names)
                changed[k] = wrong
                variants[f"{label} {k}"] = changed
        for label, joints in variants.items():
            arms = list(plan.arms)
            arms[i] = dataclasses.replace(arm, joints=tuple(joints))
            first = next(k for k in range(6) if joints[k] != names[k])
            yield Mutant(
                "joint names",
                f"{arm.name} {label}",
                dataclasses.replace(plan, arms=(arms[0], arms[1])),
                expect,
                mention=f"arms[{i}].joints[{first}]",
            )


def _swapped_arms(b: Base) -> Iterator[Mutant]:
    plan = b.plan
    left, right = plan.arms
    swapped_q = np.concatenate([plan.q[:, 6:], plan.q[:, :6]], axis=1)
    other = {"left": "right", "right": "left"}
    relabelled = [dataclasses.replace(e, arm=other[e.arm]) for e in plan.events]
    renamed = [
        dataclasses.replace(e, object="o2" if e.object == "o1" else "o1") for e in plan.events
    ]
    geometric = frozenset({"grasp", "collision", "joint limit"})
    yield Mutant(
        "swapped arms",
        "arms listed right first",
        dataclasses.replace(plan, arms=(right, left)),
        frozenset({"scene"}),
    )
    yield Mutant("swapped arms", "joint columns", with_q(plan, swapped_q), geometric, fine=True)
    yield Mutant("swapped arms", "event arms", with_events(plan, relabelled), geometric, fine=True)
    yield Mutant("swapped arms", "event objects", with_events(plan, renamed), geometric, fine=True)
    yield Mutant(
        "swapped arms",
        "columns and event arms",
        with_events(with_q(plan, swapped_q), relabelled),
        geometric,
        fine=True,
    )
    yield Mutant(
        "swapped arms",
        "everything",
        dataclasses.replace(with_events(with_q(plan, swapped_q), relabelled), arms=(right, left)),
        frozenset({"scene"}),
    )


def arm_offsets(b: Base) -> Iterator[Mutant]:
    """Constant joint offsets of one arm: the same dynamics, other places; they miss the
    grasp or hit something first (some of them the other arm: checked in a test below)."""
    for arm, (dp, dl, de) in itertools.product(
        (0, 6), itertools.product((-0.4, 0.4), (0.0, 0.3), (-0.6, -0.3, 0.0))
    ):
        if dp == dl == de == 0.0:
            continue
        q = np.array(b.plan.q)
        q[:, arm : arm + 3] += (dp, dl, de)
        yield Mutant(
            "arm offset",
            f"{arm} {dp} {dl} {de}",
            with_q(b.plan, q),
            frozenset({"collision", "grasp", "joint limit"}),
            fine=True,
        )


def _objects(b: Base) -> Iterator[Mutant]:
    plan, instance = b.plan, b.instance
    o1, o2, o3 = instance.objects

    def with_objects(*objects: ObjectSpec) -> Instance:
        return dataclasses.replace(instance, objects=objects)

    # o3 where o1 or o2 is placed: the place lands on it (or the carried object hits it)
    for target in (o1, o2):
        for dx, dy in ((0.0, 0.0), (0.03, 0.0), (0.0, 0.03), (-0.05, 0.0)):
            g = target.goal
            at = Pose2D(g.x + dx, g.y + dy, o3.start.yaw)
            moved = dataclasses.replace(o3, start=at, goal=at)
            yield Mutant(
                "object collision",
                f"o3 at {target.name}'s goal {dx} {dy}",
                plan,
                frozenset({"release", "collision"}),
                instance=with_objects(o1, o2, moved),
                fine=True,
            )
    # goals elsewhere: the objects end away from them
    for obj, (dx, dy, dyaw) in itertools.product(
        (0, 1), ((0.002, 0.0, 0.0), (0.0, -0.005, 0.0), (0.02, 0.02, 0.0), (0.0, 0.0, 0.03))
    ):
        objects = list(instance.objects)
        g = objects[obj].goal
        objects[obj] = dataclasses.replace(
            objects[obj], goal=Pose2D(g.x + dx, g.y + dy, g.yaw + dyaw)
        )
        yield Mutant(
            "object goal",
            f"o{obj + 1} goal {dx} {dy} {dyaw}",
            plan,
            frozenset({"goal"}),
            instance=with_objects(*objects),
            fine=True,
        )
    for name, (dx, dyaw) in itertools.product(("o1", "o2"), ((0.002, 0.0), (0.0, 0.03))):
        final = dict(plan.final_poses)
        x, y, yaw = final[name]
        final[name] = (x + dx, y, yaw + dyaw)
        yield Mutant(
            "object goal",
            f"final_poses {name} {dx} {dyaw}",
            dataclasses.replace(plan, final_poses=final),
            frozenset({"final poses"}),
            fine=True,
        )
    # a workspace without the goals: the releases leave it
    for ws in (Workspace((-0.25, 0.1), (-0.3, 0.3)), Workspace((-0.25, 0.25), (-0.1, 0.3))):
        yield Mutant(
            "object goal",
            f"workspace {ws}",
            plan,
            frozenset({"release"}),
            instance=dataclasses.replace(instance, workspace=ws),
            fine=True,
            mention="leaves the workspace",
        )


def _scene_and_instance(b: Base) -> Iterator[Mutant]:
    plan, instance = b.plan, b.instance
    yield Mutant(
        "scene, instance",
        "name",
        plan,
        frozenset({"instance"}),
        instance=dataclasses.replace(instance, name="D4"),
    )
    yield Mutant(
        "scene, instance",
        "o3 missing",
        plan,
        frozenset({"instance"}),
        instance=dataclasses.replace(instance, objects=instance.objects[:2]),
    )
    for i, key in itertools.product((0, 1), ("T_world_base", "T_tool0_tcp", "home")):
        value = np.array(getattr(plan.arms[i], key))
        value.flat[3 if key != "T_tool0_tcp" else 11] += 0.01  # x of the base, z of the tool
        arms = list(plan.arms)
        arms[i] = dataclasses.replace(arms[i], **{key: value})
        yield Mutant(
            "scene, instance",
            f"arms[{i}].{key}",
            dataclasses.replace(plan, arms=(arms[0], arms[1])),
            frozenset({"scene"}),
            mention=f"arms[{i}].{key}",
        )


def _gripper_events(b: Base) -> Iterator[Mutant]:
    plan = b.plan
    for i, e in enumerate(plan.events):
        for axis, size in ((0, 0.002), (2, -0.0015)):
            T = np.array(e.T_tcp_object)
            T[axis, 3] += size
            events = list(plan.events)
            events[i] = dataclasses.replace(e, T_tcp_object=T)
            yield Mutant(
                "gripper",
                f"{e.arm} {e.type} T moved {axis}",
                with_events(plan, events),
                frozenset({e.type}),
                fine=True,
            )
        T = np.array(e.T_tcp_object)
        T[:3, :3] = T[:3, :3] @ _rot_x(math.radians(1.5))
        events = list(plan.events)
        events[i] = dataclasses.replace(e, T_tcp_object=T)
        yield Mutant(
            "gripper",
            f"{e.arm} {e.type} T turned",
            with_events(plan, events),
            frozenset({e.type}),
            fine=True,
        )
        events = list(plan.events)
        events[i] = dataclasses.replace(e, type="release" if e.type == "grasp" else "grasp")
        yield Mutant(
            "gripper",
            f"{e.arm} {e.type} flipped",
            with_events(plan, events),
            frozenset({"grasp", "release"}),
            fine=True,
        )
        events = [x for k, x in enumerate(plan.events) if k != i]
        expect = {"held"} if e.type == "release" else {"release", "collision"}
        yield Mutant(
            "gripper",
            f"{e.arm} {e.type} removed",
            with_events(plan, events),
            frozenset(expect),
            fine=True,
        )


def _rot_x(a: float) -> FloatArray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _drops(b: Base) -> Iterator[Mutant]:
    """A pause where the robot passes through rest while carrying, and one arm opens its
    gripper there: the object would fall."""
    plan = b.plan
    for k in rest_junctions(plan)[:3]:
        paused = insert_still(plan, k, 25)
        t_k = float(paused.t[k])
        for arm in ARMS:
            events = [
                dataclasses.replace(e, t=t_k) if (e.arm, e.type) == (arm, "release") else e
                for e in paused.events
            ]
            yield Mutant(
                "drop",
                f"{arm} opens at {t_k:.2f}",
                with_events(paused, events),
                frozenset({"release"}),
                mention="rest flat on the table",
                fine=True,
            )


WORLD_FAMILIES: tuple[Callable[[Base], Iterator[Mutant]], ...] = (
    _joint_names,
    _swapped_arms,
    arm_offsets,
    _objects,
    _scene_and_instance,
    _gripper_events,
    _drops,
)
