"""Mutation test of the independent validator.

A valid dual-arm plan is made once with the planning streams (both arms pick at once, carry
at once and place at once; o3 never moves). Several hundred mutants of it, each breaking one
rule (limits by a few percent, dwells, event times, jumps, time stamps, non-finite values,
joint names, swapped arms, collisions, misplaced objects, drops in mid-air ...), must all be
rejected with a violation of a relevant kind; plans changed in ways that keep them valid
(slower, longer pauses, exact limits) must be accepted.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from sdar_tamp.cli import main
from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_building import GripperEvent, MotionSegment, build_plan_file
from sdar_tamp.plan_file import GRIPPER_DWELL, PlanEvent, PlanFile, PlanFileError
from sdar_tamp.plan_reading import load_plan
from sdar_tamp.plan_writing import plan_to_dict, save_plan
from sdar_tamp.replay import PlanValidator, ReplayReport, validate_plan
from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D, parse_instance
from sdar_tamp.world.scene import JOINT_KEYS, Scene, Workspace
from sdar_tamp.world.transforms import FloatArray, inverse, pose_xyz_yaw
from streams.context import WorldContext
from streams.grasps import sample_grasps
from streams.ik import IKRequest, solve_ik_candidates
from streams.motion.exact_check import HeldObject
from streams.motion.ladder import plan_dual_motion
from streams.motion.optimiser_cache import OptimiserCache
from streams.motion.planner import MotionPlanner
from streams.motion.records import MotionRequest, MotionResult
from streams.motion.shape import ShapeOptions

INSTANCE = """name: D3
workspace: {x: [-0.25, 0.25], y: [-0.3, 0.3]}
objects:
  - {name: o1, size: [0.08, 0.04, 0.05], start: [-0.15, 0.15, 0.3], goal: [-0.12, -0.15, 1.2]}
  - {name: o2, size: [0.08, 0.04, 0.05], start: [0.12, -0.1, 0.9], goal: [0.15, 0.18, 2.0]}
  - {name: o3, size: [0.08, 0.04, 0.05], start: [0.0, 0.0, 1.57], goal: [0.0, 0.0, 1.57]}
"""
ARMS = {"left": "o1", "right": "o2"}
JOINTS = [f"{arm} {k}" for arm in ARMS for k in JOINT_KEYS]  # as violation messages name them
HOME_PAUSE = 25  # samples (0.5 s) of standing still added in some valid mutants


@dataclass(frozen=True)
class Base:
    ctx: WorldContext
    instance: Instance
    plan: PlanFile
    fine: PlanValidator  # 5 mm TCP steps, as `sdar validate`
    coarse: PlanValidator  # 5 cm TCP steps: for mutants aimed at the timeline rules


@dataclass(frozen=True)
class Mutant:
    """An invalid plan (or instance, or scene) and the violation kinds that may report it;
    ``mention``: text the message must contain."""

    family: str
    name: str
    plan: PlanFile
    expect: frozenset[str]
    instance: Instance | None = None
    scene: Scene | None = None
    mention: str = ""
    fine: bool = False  # replay with 5 mm steps (geometric mutants)


def _box(o: ObjectSpec, p: Pose2D) -> ObjectBox:
    return ObjectBox(pose_xyz_yaw(p.x, p.y, o.size[2] / 2, p.yaw), o.size)


def _segment(result: MotionResult, kind: str) -> MotionSegment:
    assert result.success and result.trajectory is not None, result.reason
    traj = result.trajectory
    return MotionSegment(traj.t, traj.q, result.level or "", ("o1", "o2"), kind)


@pytest.fixture(scope="module")
def base(ctx: WorldContext, planner: MotionPlanner, optimisers: OptimiserCache) -> Base:
    instance = parse_instance(INSTANCE, "d3.yaml")
    objects = {o.name: o for o in instance.objects}
    start = {o.name: _box(o, o.start) for o in instance.objects}
    goal = {o.name: _box(o, o.goal) for o in instance.objects}
    home = {a: ctx.home(a) for a in ctx.arm_names}
    world = ctx.new_world()
    pick, place, T_tcp_obj, held = {}, {}, {}, {}
    for arm, name in ARMS.items():
        grasps = sample_grasps(objects[name].size, ctx.scene.grasp_limits)
        at_start = solve_ik_candidates(
            ctx, world, start, [IKRequest(arm, name, start[name], grasps)], home
        )
        at_goal = solve_ik_candidates(
            ctx, world, goal, [IKRequest(arm, name, goal[name], grasps)], home
        )
        a, b = next((a, b) for a in at_start for b in at_goal if a.grasp is b.grasp)
        pick[arm], place[arm] = a.q, b.q
        T_tcp_obj[arm] = inverse(a.grasp.T_object_tcp)
        T_tool0_obj = ctx.kinematics[arm].T_tool0_tcp @ T_tcp_obj[arm]
        held[arm] = HeldObject(name, objects[name].size, T_tool0_obj)
    h12 = np.concatenate([home["left"], home["right"]])
    q_pick = np.concatenate([pick["left"], pick["right"]])
    q_place = np.concatenate([place["left"], place["right"]])
    both = (True, True)
    requests = [
        MotionRequest(h12, q_pick, start, approach=both),
        MotionRequest(q_pick, q_place, {"o3": start["o3"]}, held, both, both),
        MotionRequest(q_place, h12, goal, retreat=both),
    ]
    # the carrying motion is not blended: it passes through rest at its lifted points, where
    # the "drop" mutants pause; the others are blended (no stop at the pre-grasp points)
    unblended = MotionPlanner(ctx, shape=ShapeOptions(blend=False), optimisers=optimisers)
    a, b, c = (
        plan_dual_motion(p, r) for p, r in zip((planner, unblended, planner), requests, strict=True)
    )
    assert a.blended and c.blended and not b.blended
    items: list[MotionSegment | GripperEvent] = [
        _segment(a, "pick"),
        *(GripperEvent(arm, "grasp", name, T_tcp_obj[arm]) for arm, name in ARMS.items()),
        _segment(b, "place"),
        *(GripperEvent(arm, "release", name, T_tcp_obj[arm]) for arm, name in ARMS.items()),
        _segment(c, "retreat"),
    ]
    plan = build_plan_file(
        ctx.scene,
        instance.name,
        {o.name: o.start.as_tuple() for o in instance.objects},
        {o.name: o.size for o in instance.objects},
        items,
        {},
    )
    fine, coarse = PlanValidator(ctx.scene), PlanValidator(ctx.scene, max_tcp_step=0.05)
    return Base(ctx, instance, plan, fine, coarse)


# -- helpers ---------------------------------------------------------------------------------
def _index(plan: PlanFile, t: float) -> int:
    k = int(np.argmin(np.abs(plan.t - t)))
    assert abs(plan.t[k] - t) < 1e-12, "events of the base plan sit on samples"
    return k


def _rebuild(plan: PlanFile, keep: FloatArray, t: FloatArray, q: FloatArray) -> PlanFile:
    """``plan`` with new samples; ``keep[k]``: the new index of old sample ``k`` (events
    follow their sample)."""
    events = tuple(
        dataclasses.replace(e, t=float(t[int(keep[_index(plan, e.t)])])) for e in plan.events
    )
    return dataclasses.replace(plan, t=t, q=q, events=events)


def _retime(plan: PlanFile, h: FloatArray) -> PlanFile:
    """The same samples with the spacings ``h`` ``(n - 1,)`` [s]."""
    t = np.concatenate([[0.0], np.cumsum(h)])
    return _rebuild(plan, np.arange(len(t)), t, np.array(plan.q))


def _insert_still(plan: PlanFile, k: int, n: int) -> PlanFile:
    """Stand still ``n`` samples of 0.02 s at sample ``k`` (later samples and events move)."""
    t, q = plan.t, plan.q
    t_new = np.concatenate([t[: k + 1], t[k] + 0.02 * np.arange(1, n + 1), t[k + 1 :] + 0.02 * n])
    q_new = np.concatenate([q[: k + 1], np.repeat(q[k : k + 1], n, axis=0), q[k + 1 :]])
    keep = np.arange(len(t)) + np.where(np.arange(len(t)) > k, n, 0)
    return _rebuild(plan, keep, t_new, q_new)


def _remove(plan: PlanFile, first: int, count: int) -> PlanFile:
    """Drop samples ``first .. first + count - 1`` (no event on them); later ones move up by
    the time they spanned."""
    t, q = plan.t, plan.q
    shift = t[first + count] - t[first - 1] - (t[first + count] - t[first + count - 1])
    keep_mask = np.ones(len(t), bool)
    keep_mask[first : first + count] = False
    t_new = np.where(np.arange(len(t)) >= first + count, t - shift, t)[keep_mask]
    keep = np.cumsum(keep_mask) - 1
    return _rebuild(plan, keep, t_new, q[keep_mask])


def _with_q(plan: PlanFile, q: FloatArray) -> PlanFile:
    return dataclasses.replace(plan, q=q)


def _events(plan: PlanFile, events: list[PlanEvent]) -> PlanFile:
    return dataclasses.replace(plan, events=tuple(sorted(events, key=lambda e: e.t)))


def _velocity(plan: PlanFile) -> FloatArray:
    return np.diff(plan.q, axis=0) / np.diff(plan.t)[:, None]


def _acceleration(plan: PlanFile) -> FloatArray:
    """At every sample, the robot at rest before and after (as the validator measures)."""
    h = np.diff(plan.t)
    rest = np.zeros((1, 12))
    v = np.concatenate([rest, _velocity(plan), rest])
    h2 = np.concatenate([h[:1], h, h[-1:]])
    out: FloatArray = np.diff(v, axis=0) / (0.5 * (h2[1:] + h2[:-1]))[:, None]
    return out


def _instants(plan: PlanFile) -> list[float]:
    return sorted({e.t for e in plan.events})


def _moving(plan: PlanFile) -> FloatArray:
    """Per interval: does any joint move?"""
    out: FloatArray = np.abs(np.diff(plan.q, axis=0)).max(axis=1) > 0.0
    return out


def _scene_arms(scene: Scene, j: int, field: str, value: float) -> Scene:
    """``scene`` with joint ``j`` (0..11) of ``field`` (a per-joint tuple) set to ``value``."""
    arms = list(scene.arms)
    arm = arms[j // 6]
    values = list(getattr(arm, field))
    values[j % 6] = value
    arms[j // 6] = dataclasses.replace(arm, **{field: tuple(values)})
    return dataclasses.replace(scene, arms=tuple(arms))


def _smooth_bump(n: int) -> FloatArray:
    """``(n,)`` from 0 up to 1 and back to 0, smoothly (sin^2)."""
    out: FloatArray = np.sin(np.linspace(0.0, np.pi, n)) ** 2
    return out


def _rest_junctions(plan: PlanFile) -> list[int]:
    """Samples strictly inside the carrying segment where the robot passes through rest (the
    fastest joint of both neighbouring intervals <= 0.06 rad/s, moving on both sides)."""
    t_grasp, t_release = _instants(plan)
    k0, k1 = _index(plan, t_grasp) + 26, _index(plan, t_release) - 1
    speed = np.abs(_velocity(plan)).max(axis=1)
    moving = _moving(plan)
    return [
        k
        for k in range(k0, k1)
        if speed[k - 1] <= 0.06
        and speed[k] <= 0.06
        and moving[k - 1]
        and moving[k]
        and speed[k - 1] + speed[k] <= min(speed[k - 2], speed[k + 1])
    ]


# -- mutant families ---------------------------------------------------------------------------
def _joint_limits(b: Base) -> Iterator[Mutant]:
    scene, q = b.ctx.scene, b.plan.q
    for j, name in enumerate(JOINTS):
        for delta in (1e-7,):
            hi, lo = float(q[:, j].max()), float(q[:, j].min())
            for field, value in (("upper", hi - delta), ("lower", lo + delta)):
                yield Mutant(
                    "joint limit",
                    f"scene {name} {field} {delta}",
                    b.plan,
                    frozenset({"joint limit"}),
                    scene=_scene_arms(scene, j, field, value),
                    mention=name,
                )
        limits = scene.arms[j // 6]
        for sign in (1.0, -1.0):
            edge = limits.upper[j % 6] if sign > 0 else limits.lower[j % 6]
            far = float(q[:, j].max() if sign > 0 else q[:, j].min())
            if abs(edge) > 3.0:  # +-pi joints: the offset would be a large rotation
                continue
            moved = np.array(q)
            moved[:, j] += edge - far + sign * 1e-3
            yield Mutant(
                "joint limit",
                f"plan {name} {sign:+.0f}",
                _with_q(b.plan, moved),
                frozenset({"joint limit", "grasp", "collision"}),
                fine=True,
            )


def _velocity_limits(b: Base) -> Iterator[Mutant]:
    scene, v = b.ctx.scene, np.abs(_velocity(b.plan))
    for j, name in enumerate(JOINTS):
        peak = float(v[:, j].max())
        if peak < 0.1:
            continue
        for eps in (1e-4,):
            yield Mutant(
                "velocity",
                f"scene {name} {eps}",
                b.plan,
                frozenset({"velocity"}),
                scene=_scene_arms(scene, j, "velocity_limit", peak / (1.0 + eps)),
                mention=name,
            )
        v_max = scene.arms[j // 6].velocity_limit[j % 6]
        i = int(np.argmax(v[:, j]))
        for eps in (0.01, 0.03, 0.05):
            h = np.diff(b.plan.t)
            h[i] *= peak / (v_max * (1.0 + eps))  # this one interval is run faster
            yield Mutant(
                "velocity", f"plan {name} {eps}", _retime(b.plan, h), frozenset({"velocity"})
            )


def _acceleration_limits(b: Base) -> Iterator[Mutant]:
    scene, plan = b.ctx.scene, b.plan
    acc = np.abs(_acceleration(plan))
    a_max = np.concatenate([a.acceleration_limit for a in scene.arms])
    v_max = np.concatenate([a.velocity_limit for a in scene.arms])
    a_ratio = float((acc / a_max).max())
    v_ratio = float((np.abs(_velocity(plan)) / v_max).max())
    for eps in (1e-5, 1e-3, 0.01, 0.02, 0.03, 0.05, 0.24):
        s = math.sqrt(a_ratio / (1.0 + eps))  # motion (not the dwells) runs 1/s times faster
        expect = {"acceleration"} | ({"velocity"} if v_ratio / s > 1.0 else set())
        h = np.diff(plan.t)
        h = np.where(_moving(plan), h * s, h)
        yield Mutant("acceleration", f"faster motion {eps}", _retime(plan, h), frozenset(expect))
    for j, name in enumerate(JOINTS):
        peak = float(acc[:, j].max())
        if peak < 0.5:
            continue
        for eps in (1e-4,):
            yield Mutant(
                "acceleration",
                f"scene {name} {eps}",
                plan,
                frozenset({"acceleration"}),
                scene=_scene_arms(scene, j, "acceleration_limit", peak / (1.0 + eps)),
                mention=name,
            )
    # the plan ends, or starts, in full motion
    moving = _moving(plan)
    last = _index(plan, _instants(plan)[-1]) + 26
    for k in (last + 10, last + 20, last + 30):
        assert moving[k - 1]
        cut = dataclasses.replace(plan, t=plan.t[: k + 1], q=plan.q[: k + 1])
        yield Mutant(
            "acceleration",
            f"ends moving at {k}",
            cut,
            frozenset({"acceleration"}),
            mention="when the plan ends",
        )
    first = int(np.argmax(moving))
    for k in (2, 3, 5):
        late = _remove(plan, first + 1, k)  # the first k motion samples gone: starts fast
        late = dataclasses.replace(late, t=late.t[first:] - late.t[first], q=late.q[first:])
        events = tuple(dataclasses.replace(e, t=e.t - plan.t[first]) for e in late.events)
        yield Mutant(
            "acceleration",
            f"starts moving {k}",
            dataclasses.replace(late, events=events),
            frozenset({"acceleration"}),
            mention="when it starts",
        )


def _dwells(b: Base) -> Iterator[Mutant]:
    plan = b.plan
    for t_e in _instants(plan):
        k = _index(plan, t_e)
        for n in (1, 2, 3, 5, 8, 12, 17, 21, 24, 25):  # 0.02 .. 0.5 s of the dwell removed
            yield Mutant(
                "dwell", f"t={t_e:.2f} minus {n}", _remove(plan, k + 1, n), frozenset({"dwell"})
            )
        for factor in (0.99, 0.999, 0.9999):
            h = np.diff(plan.t)
            h[k : k + 25] *= factor
            yield Mutant("dwell", f"t={t_e:.2f} x{factor}", _retime(plan, h), frozenset({"dwell"}))
        for j, name in enumerate(JOINTS):  # either arm moves a little during the dwell
            q = np.array(plan.q)
            q[k : k + 26, j] += 1e-4 * _smooth_bump(26)
            yield Mutant(
                "dwell",
                f"t={t_e:.2f} {name} moves",
                _with_q(plan, q),
                frozenset({"dwell"}),
                mention=name,
            )
    # a second action of one gripper within the dwell
    grasp = plan.events[0]
    for dt in (0.0, 0.1, 0.3):
        again = dataclasses.replace(grasp, t=grasp.t + dt, type="release")
        yield Mutant(
            "dwell",
            f"release {dt} s after grasp",
            _events(plan, [*plan.events, again]),
            frozenset({"dwell"}),
        )
    # the plan ends before a dwell is over
    t_r = _instants(plan)[-1]
    k = _index(plan, t_r)
    for n in (0, 5, 24):
        cut = dataclasses.replace(plan, t=plan.t[: k + n + 1], q=plan.q[: k + n + 1])
        yield Mutant("dwell", f"ends {n} samples after release", cut, frozenset({"dwell"}))


def _moved_events(b: Base) -> Iterator[Mutant]:
    plan = b.plan
    shifts = (-0.5, -0.1, -0.02, -0.001, 0.001, 0.02, 0.1, 0.49, 1.0)
    expect = frozenset({"dwell", "grasp", "release"})
    for i, e in enumerate(plan.events):
        for dt in shifts:
            events = list(plan.events)
            events[i] = dataclasses.replace(e, t=e.t + dt)
            yield Mutant("event moved", f"{e.arm} {e.type} {dt:+}", _events(plan, events), expect)
    for t_e in _instants(plan):
        for dt in shifts:
            events = [dataclasses.replace(e, t=e.t + dt) if e.t == t_e else e for e in plan.events]
            yield Mutant("event moved", f"t={t_e:.2f} {dt:+}", _events(plan, events), expect)


def _jumps(b: Base) -> Iterator[Mutant]:
    plan = b.plan
    moving = _moving(plan)
    inside_motion = int(np.flatnonzero(moving)[40])
    inside_dwell = _index(plan, _instants(plan)[0]) + 10
    expect = frozenset({"velocity", "acceleration", "dwell", "joint limit"})
    for j, name in enumerate(JOINTS):
        for k, size, kind in itertools.product(
            (inside_motion, inside_dwell), (0.01, -0.1), ("spike", "step")
        ):
            q = np.array(plan.q)
            if kind == "spike":
                q[k, j] += size
            else:
                q[k:, j] += size
            yield Mutant("jump", f"{kind} {name} {size} at {k}", _with_q(plan, q), expect)


def _time_stamps(b: Base) -> Iterator[Mutant]:
    plan = b.plan
    n = len(plan.t)
    expect = frozenset({"format"})
    for k in (1, n // 3, n // 2, n - 1):
        edits: dict[str, Callable[[FloatArray], None]] = {
            "repeated": lambda t, k=k: t.__setitem__(k, t[k - 1]),
            "backwards": lambda t, k=k: t.__setitem__(k, t[k - 1] - 0.001),
            "gap": lambda t, k=k: t.__setitem__(slice(k, None), t[k:] + 0.021),
        }
        for name, edit in edits.items():
            t = np.array(plan.t)
            edit(t)
            events = tuple(
                e if e.t <= t[-1] else dataclasses.replace(e, t=float(t[-1])) for e in plan.events
            )
            yield Mutant(
                "time",
                f"{name} at {k}",
                dataclasses.replace(plan, t=t, events=events),
                expect,
                mention=f"trajectory.t[{k}]",
            )
    t = np.array(plan.t)
    t[[n // 2, n // 2 + 1]] = t[[n // 2 + 1, n // 2]]
    yield Mutant("time", "swapped", dataclasses.replace(plan, t=t), expect)
    yield Mutant("time", "late start", dataclasses.replace(plan, t=plan.t + 0.01), expect)
    for t_bad in (-0.1, plan.duration + 0.01):
        events = list(plan.events)
        events[-1] = dataclasses.replace(events[-1], t=t_bad)
        yield Mutant(
            "time", f"event at {t_bad:.2f}", dataclasses.replace(plan, events=tuple(events)), expect
        )
    unsorted = (plan.events[2], *plan.events[:2], *plan.events[3:])
    yield Mutant("time", "events unsorted", dataclasses.replace(plan, events=unsorted), expect)


def _non_finite(b: Base) -> Iterator[Mutant]:
    plan = b.plan
    n = len(plan.t)
    expect = frozenset({"format"})
    for value in (math.nan, math.inf, -math.inf):
        for k, j in ((0, 0), (n // 2, 7), (n - 1, 11)):
            q = np.array(plan.q)
            q[k, j] = value
            yield Mutant(
                "non-finite",
                f"q[{k},{j}]={value}",
                _with_q(plan, q),
                expect,
                mention=f"trajectory.q[{k}]",
            )
        t = np.array(plan.t)
        t[n // 2] = value
        yield Mutant("non-finite", f"t={value}", dataclasses.replace(plan, t=t), expect)
        e = plan.events[1]
        T = np.array(e.T_tcp_object)
        T[0, 3] = value
        events = (plan.events[0], dataclasses.replace(e, T_tcp_object=T), *plan.events[2:])
        yield Mutant(
            "non-finite", f"T_tcp_object {value}", dataclasses.replace(plan, events=events), expect
        )
        events = (plan.events[0], dataclasses.replace(e, t=value), *plan.events[2:])
        yield Mutant(
            "non-finite", f"event t {value}", dataclasses.replace(plan, events=events), expect
        )
        final = dict(plan.final_poses)
        final["o1"] = (value, 0.0, 0.0)
        yield Mutant(
            "non-finite",
            f"final pose {value}",
            dataclasses.replace(plan, final_poses=final),
            expect,
        )
        for i, key in itertools.product((0, 1), ("T_world_base", "home")):
            value_array = np.array(getattr(plan.arms[i], key))
            value_array.flat[3] = value
            arms = list(plan.arms)
            arms[i] = dataclasses.replace(arms[i], **{key: value_array})
            yield Mutant(
                "non-finite",
                f"arms[{i}].{key} {value}",
                dataclasses.replace(plan, arms=(arms[0], arms[1])),
                frozenset({"scene"}),
                mention=f"arms[{i}].{key}",
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
    yield Mutant("swapped arms", "joint columns", _with_q(plan, swapped_q), geometric, fine=True)
    yield Mutant("swapped arms", "event arms", _events(plan, relabelled), geometric, fine=True)
    yield Mutant("swapped arms", "event objects", _events(plan, renamed), geometric, fine=True)
    yield Mutant(
        "swapped arms",
        "columns and event arms",
        _events(_with_q(plan, swapped_q), relabelled),
        geometric,
        fine=True,
    )
    yield Mutant(
        "swapped arms",
        "everything",
        dataclasses.replace(_events(_with_q(plan, swapped_q), relabelled), arms=(right, left)),
        frozenset({"scene"}),
    )


def _arm_offsets(b: Base) -> Iterator[Mutant]:
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
            _with_q(b.plan, q),
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
                _events(plan, events),
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
            _events(plan, events),
            frozenset({e.type}),
            fine=True,
        )
        events = list(plan.events)
        events[i] = dataclasses.replace(e, type="release" if e.type == "grasp" else "grasp")
        yield Mutant(
            "gripper",
            f"{e.arm} {e.type} flipped",
            _events(plan, events),
            frozenset({"grasp", "release"}),
            fine=True,
        )
        events = [x for k, x in enumerate(plan.events) if k != i]
        expect = {"held"} if e.type == "release" else {"release", "collision"}
        yield Mutant(
            "gripper",
            f"{e.arm} {e.type} removed",
            _events(plan, events),
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
    for k in _rest_junctions(plan)[:3]:
        paused = _insert_still(plan, k, 25)
        t_k = float(paused.t[k])
        for arm in ARMS:
            events = [
                dataclasses.replace(e, t=t_k) if (e.arm, e.type) == (arm, "release") else e
                for e in paused.events
            ]
            yield Mutant(
                "drop",
                f"{arm} opens at {t_k:.2f}",
                _events(paused, events),
                frozenset({"release"}),
                mention="rest flat on the table",
                fine=True,
            )


FAMILIES: tuple[Callable[[Base], Iterator[Mutant]], ...] = (
    _joint_limits,
    _velocity_limits,
    _acceleration_limits,
    _dwells,
    _moved_events,
    _jumps,
    _time_stamps,
    _non_finite,
    _joint_names,
    _swapped_arms,
    _arm_offsets,
    _objects,
    _scene_and_instance,
    _gripper_events,
    _drops,
)


def _validate(b: Base, m: Mutant) -> ReplayReport:
    instance = m.instance or b.instance
    if m.scene is not None:
        return PlanValidator(m.scene, max_tcp_step=0.05).validate(instance, m.plan)
    return (b.fine if m.fine else b.coarse).validate(instance, m.plan)


# -- tests -------------------------------------------------------------------------------------
def test_the_base_plan_is_valid(base: Base) -> None:
    report = base.fine.validate(base.instance, base.plan)
    assert report.ok, report.violation
    assert [(e.arm, e.type) for e in base.plan.events] == [
        ("left", "grasp"),
        ("right", "grasp"),
        ("left", "release"),
        ("right", "release"),
    ]
    assert base.plan.metrics.dual_arm_steps == 3
    assert len(_rest_junctions(base.plan)) >= 1


def test_every_invalid_mutant_is_rejected_with_a_relevant_violation(base: Base) -> None:
    mutants = [m for family in FAMILIES for m in family(base)]
    wrong: list[str] = []
    kinds: Counter[str] = Counter()
    for m in mutants:
        v = _validate(base, m).violation
        if v is None:
            wrong.append(f"{m.family} / {m.name}: accepted")
        elif v.kind not in m.expect or m.mention not in v.message:
            wrong.append(f"{m.family} / {m.name}: {v.kind}: {v.message}")
        else:
            kinds[v.kind] += 1
    assert wrong == [], f"{len(wrong)} of {len(mutants)} mutants:\n" + "\n".join(wrong)
    assert len(mutants) >= 400
    families = Counter(m.family for m in mutants)
    assert min(families.values()) >= 4, families
    every_kind = {
        "format",
        "scene",
        "instance",
        "joint limit",
        "velocity",
        "acceleration",
        "dwell",
        "collision",
        "grasp",
        "release",
        "held",
        "goal",
        "final poses",
    }
    assert every_kind <= set(kinds), every_kind - set(kinds)


def test_some_arm_offsets_make_the_arms_collide(base: Base) -> None:
    """Arm against arm (not a gripper against the table or an object)."""
    between: list[str] = []
    for m in _arm_offsets(base):
        v = _validate(base, m).violation
        assert v is not None
        text = v.message
        if text.startswith("arms "):  # the arms in contact, then the shapes
            assert text.startswith("arms left and right in contact: "), text
            text = text.split(": ", 1)[1]
        pairs = [p.split(" with ") for p in text.split(", ") if " with " in p]
        sides = [{a.split("_")[0], c.split("_")[0]} for a, c in pairs]
        if v.kind == "collision" and {"left", "right"} in sides:
            between.append(m.name)
    assert len(between) >= 1


def _slower(plan: PlanFile, k: int) -> PlanFile:
    """Everything ``k`` times slower, every interval cut into ``k`` equal ones."""
    t, q = plan.t, plan.q
    frac = np.arange(k) / k
    t_new = np.append((t[:-1, None] + frac * np.diff(t)[:, None]).ravel(), t[-1]) * k
    q_new = np.concatenate(
        [(q[:-1, None] + frac[:, None] * np.diff(q, axis=0)[:, None]).reshape(-1, 12), q[-1:]]
    )
    return _rebuild(plan, np.arange(len(t)) * k, t_new, q_new)


def _valid_variants(b: Base) -> Iterator[tuple[str, PlanFile, Scene | None]]:
    plan, scene = b.plan, b.ctx.scene
    yield "slower x2", _slower(plan, 2), None
    yield "slower x3", _slower(plan, 3), None
    for t_e in _instants(plan):
        yield f"longer dwell at {t_e:.2f}", _insert_still(plan, _index(plan, t_e), 10), None
    yield "still at the start", _insert_still(plan, 0, HOME_PAUSE), None
    yield "still at the end", _insert_still(plan, len(plan.t) - 1, HOME_PAUSE), None
    for k in _rest_junctions(plan)[:3]:
        yield f"pause at rest {k}", _insert_still(plan, k, HOME_PAUSE), None
    final = dict(plan.final_poses)
    x, y, yaw = final["o1"]
    final["o1"] = (x, y, yaw - math.pi)
    yield "final yaw - pi", dataclasses.replace(plan, final_poses=final), None
    # limits exactly at what the plan uses
    v, a = np.abs(_velocity(plan)), np.abs(_acceleration(plan))
    for j in range(12):
        at = _scene_arms(scene, j, "velocity_limit", float(v[:, j].max()) or 1.0)
        at = _scene_arms(at, j, "acceleration_limit", float(a[:, j].max()) or 1.0)
        at = _scene_arms(at, j, "upper", float(plan.q[:, j].max()))
        at = _scene_arms(at, j, "lower", float(plan.q[:, j].min()))
        yield f"limits at the plan's extremes, {JOINTS[j]}", plan, at


def test_valid_preserving_mutants_are_accepted(base: Base) -> None:
    names = []
    for name, plan, scene in _valid_variants(base):
        if scene is None:
            report = base.coarse.validate(base.instance, plan)
        else:
            report = PlanValidator(scene, max_tcp_step=0.05).validate(base.instance, plan)
        assert report.ok, f"{name}: {report.violation}"
        names.append(name)
    assert len(names) >= 20
    slower = _slower(base.plan, 2)
    assert slower.duration == pytest.approx(2 * base.plan.duration)
    assert base.fine.validate(base.instance, slower).ok


def test_a_plan_file_round_trip_stays_valid(base: Base, tmp_path: Path) -> None:
    plan = load_plan(save_plan(base.plan, tmp_path / "plan.json"))
    assert base.fine.validate(base.instance, plan).ok


def test_mutant_files_are_refused_by_the_loader_and_the_command_line(
    base: Base, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Non-finite numbers and times out of order cannot even be loaded (exit status 2);
    wrong joint names load and are invalid (exit status 1)."""
    instance = tmp_path / "d3.yaml"
    instance.write_text(INSTANCE)
    data = plan_to_dict(base.plan)

    def nan(d: dict[str, Any]) -> None:
        d["trajectory"]["q"][3][2] = math.nan

    def repeated_time(d: dict[str, Any]) -> None:
        d["trajectory"]["t"][5] = d["trajectory"]["t"][4]

    edits = {"nan": nan, "repeated time": repeated_time}
    for name, edit in edits.items():
        bad = json.loads(json.dumps(data))
        edit(bad)
        path = tmp_path / f"{name}.json"
        path.write_text(json.dumps(bad))  # NaN written as the (non-JSON) token NaN
        with pytest.raises(PlanFileError, match=r"trajectory\.(q\[3\]\[2\]|t\[5\])"):
            load_plan(path)
        assert main(["validate", str(instance), str(path)]) == 2
    joints = list(data["arms"][1]["joints"])
    joints[2], joints[3] = joints[3], joints[2]
    data["arms"][1]["joints"] = joints
    path = tmp_path / "joints.json"
    path.write_text(json.dumps(data))
    capsys.readouterr()
    assert main(["validate", str(instance), str(path)]) == 1
    out = capsys.readouterr().out
    assert "scene: arms[1].joints[2]: expected 'right_elbow_joint'" in out


def test_validator_parameters_are_checked(base: Base) -> None:
    for kwargs in (
        {"max_tcp_step": 0.0},
        {"dwell": -0.1},
        {"velocity_tolerance": -1e-6},
        {"acceleration_tolerance": math.nan},
    ):
        with pytest.raises(ParameterError, match=next(iter(kwargs))):
            PlanValidator(base.ctx.scene, **kwargs)  # type: ignore[arg-type]


def test_the_dwell_is_the_format_s_and_a_shorter_one_can_be_asked(base: Base) -> None:
    plan = _remove(base.plan, _index(base.plan, _instants(base.plan)[0]) + 1, 10)  # 0.3 s left
    report = base.coarse.validate(base.instance, plan)
    assert report.violation is not None and report.violation.kind == "dwell"
    assert report.violation.t == pytest.approx(_instants(base.plan)[0])
    assert f"still for {GRIPPER_DWELL} s" in report.violation.message
    assert validate_plan(base.instance, plan, base.ctx.scene, 0.05, dwell=0.3).ok


def test_format_rules_for_plans_built_in_memory(base: Base) -> None:
    plan = base.plan
    left, right = plan.arms
    e = plan.events[0]
    cases: dict[str, tuple[PlanFile, str]] = {
        "no samples": (
            dataclasses.replace(plan, t=np.zeros(0), q=np.zeros((0, 12)), events=()),
            "trajectory.t: expected a non-empty list",
        ),
        "q rows": (_with_q(plan, plan.q[:-1]), "trajectory.q: expected shape"),
        "q columns": (_with_q(plan, plan.q[:, :11]), "trajectory.q: expected shape"),
        "event arm": (
            _events(plan, [dataclasses.replace(e, arm="middle"), *plan.events[1:]]),
            "events[0]: expected an arm of ['left', 'right']",
        ),
        "event type": (
            _events(plan, [dataclasses.replace(e, type="squeeze"), *plan.events[1:]]),
            "and a type of ['grasp', 'release'], got 'left', 'squeeze'",
        ),
        "event transform": (
            _events(plan, [dataclasses.replace(e, T_tcp_object=2.0 * np.eye(4))]),
            "events[0].T_tcp_object: expected a finite rigid transform",
        ),
        "five joints": (
            dataclasses.replace(
                plan, arms=(left, dataclasses.replace(right, joints=right.joints[:5]))
            ),
            "arms[1].joints: the scene's arm 'right' has 6 joints",
        ),
        "seven joints": (
            dataclasses.replace(
                plan, arms=(dataclasses.replace(left, joints=(*left.joints, "x")), right)
            ),
            "arms[0].joints: the scene's arm 'left' has 6 joints",
        ),
    }
    for name, (mutant, text) in cases.items():
        report = base.coarse.validate(base.instance, mutant)
        assert report.violation is not None, name
        assert report.violation.kind in ("format", "scene") and text in report.violation.message, (
            name,
            report.violation,
        )
        assert report.checks == 0


def test_without_a_dwell_only_the_events_matter(base: Base) -> None:
    """``dwell=0``: an event may come right before the robot moves on."""
    plan = _remove(base.plan, _index(base.plan, _instants(base.plan)[0]) + 1, 25)
    assert base.coarse.validate(base.instance, plan).violation.kind == "dwell"  # type: ignore[union-attr]
    assert validate_plan(base.instance, plan, base.ctx.scene, 0.05, dwell=0.0).ok
