"""The valid dual-arm plan that the validator's mutation test breaks, and the helpers that
edit plan files for the mutants (see tests/plan/test_validator_mutations.py)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from sdar_tamp.plan_building import GripperEvent, MotionSegment, build_plan_file
from sdar_tamp.plan_file import PlanEvent, PlanFile
from sdar_tamp.replay import PlanValidator
from sdar_tamp.world.collision import ObjectBox
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D, parse_instance
from sdar_tamp.world.scene import JOINT_KEYS, Scene
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


def box(o: ObjectSpec, p: Pose2D) -> ObjectBox:
    return ObjectBox(pose_xyz_yaw(p.x, p.y, o.size[2] / 2, p.yaw), o.size)


def segment(result: MotionResult, kind: str) -> MotionSegment:
    assert result.success and result.trajectory is not None, result.reason
    traj = result.trajectory
    return MotionSegment(traj.t, traj.q, result.level or "", ("o1", "o2"), kind)


def make_base(ctx: WorldContext, planner: MotionPlanner, optimisers: OptimiserCache) -> Base:
    instance = parse_instance(INSTANCE, "d3.yaml")
    objects = {o.name: o for o in instance.objects}
    start = {o.name: box(o, o.start) for o in instance.objects}
    goal = {o.name: box(o, o.goal) for o in instance.objects}
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
        segment(a, "pick"),
        *(GripperEvent(arm, "grasp", name, T_tcp_obj[arm]) for arm, name in ARMS.items()),
        segment(b, "place"),
        *(GripperEvent(arm, "release", name, T_tcp_obj[arm]) for arm, name in ARMS.items()),
        segment(c, "retreat"),
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
def index(plan: PlanFile, t: float) -> int:
    k = int(np.argmin(np.abs(plan.t - t)))
    assert abs(plan.t[k] - t) < 1e-12, "events of the base plan sit on samples"
    return k


def rebuild(plan: PlanFile, keep: FloatArray, t: FloatArray, q: FloatArray) -> PlanFile:
    """``plan`` with new samples; ``keep[k]``: the new index of old sample ``k`` (events
    follow their sample)."""
    events = tuple(
        dataclasses.replace(e, t=float(t[int(keep[index(plan, e.t)])])) for e in plan.events
    )
    return dataclasses.replace(plan, t=t, q=q, events=events)


def retime(plan: PlanFile, h: FloatArray) -> PlanFile:
    """The same samples with the spacings ``h`` ``(n - 1,)`` [s]."""
    t = np.concatenate([[0.0], np.cumsum(h)])
    return rebuild(plan, np.arange(len(t)), t, np.array(plan.q))


def insert_still(plan: PlanFile, k: int, n: int) -> PlanFile:
    """Stand still ``n`` samples of 0.02 s at sample ``k`` (later samples and events move)."""
    t, q = plan.t, plan.q
    t_new = np.concatenate([t[: k + 1], t[k] + 0.02 * np.arange(1, n + 1), t[k + 1 :] + 0.02 * n])
    q_new = np.concatenate([q[: k + 1], np.repeat(q[k : k + 1], n, axis=0), q[k + 1 :]])
    keep = np.arange(len(t)) + np.where(np.arange(len(t)) > k, n, 0)
    return rebuild(plan, keep, t_new, q_new)


def remove(plan: PlanFile, first: int, count: int) -> PlanFile:
    """Drop samples ``first .. first + count - 1`` (no event on them); later ones move up by
    the time they spanned."""
    t, q = plan.t, plan.q
    shift = t[first + count] - t[first - 1] - (t[first + count] - t[first + count - 1])
    keep_mask = np.ones(len(t), bool)
    keep_mask[first : first + count] = False
    t_new = np.where(np.arange(len(t)) >= first + count, t - shift, t)[keep_mask]
    keep = np.cumsum(keep_mask) - 1
    return rebuild(plan, keep, t_new, q[keep_mask])


def with_q(plan: PlanFile, q: FloatArray) -> PlanFile:
    return dataclasses.replace(plan, q=q)


def with_events(plan: PlanFile, events: list[PlanEvent]) -> PlanFile:
    return dataclasses.replace(plan, events=tuple(sorted(events, key=lambda e: e.t)))


def velocity(plan: PlanFile) -> FloatArray:
    return np.diff(plan.q, axis=0) / np.diff(plan.t)[:, None]


def acceleration(plan: PlanFile) -> FloatArray:
    """At every sample, the robot at rest before and after (as the validator measures)."""
    h = np.diff(plan.t)
    rest = np.zeros((1, 12))
    v = np.concatenate([rest, velocity(plan), rest])
    h2 = np.concatenate([h[:1], h, h[-1:]])
    out: FloatArray = np.diff(v, axis=0) / (0.5 * (h2[1:] + h2[:-1]))[:, None]
    return out


def instants(plan: PlanFile) -> list[float]:
    return sorted({e.t for e in plan.events})


def moving_mask(plan: PlanFile) -> FloatArray:
    """Per interval: does any joint move?"""
    out: FloatArray = np.abs(np.diff(plan.q, axis=0)).max(axis=1) > 0.0
    return out


def scene_arms(scene: Scene, j: int, field: str, value: float) -> Scene:
    """``scene`` with joint ``j`` (0..11) of ``field`` (a per-joint tuple) set to ``value``."""
    arms = list(scene.arms)
    arm = arms[j // 6]
    values = list(getattr(arm, field))
    values[j % 6] = value
    arms[j // 6] = dataclasses.replace(arm, **{field: tuple(values)})
    return dataclasses.replace(scene, arms=tuple(arms))


def smooth_bump(n: int) -> FloatArray:
    """``(n,)`` from 0 up to 1 and back to 0, smoothly (sin^2)."""
    out: FloatArray = np.sin(np.linspace(0.0, np.pi, n)) ** 2
    return out


def rest_junctions(plan: PlanFile) -> list[int]:
    """Samples strictly inside the carrying segment where the robot passes through rest (the
    fastest joint of both neighbouring intervals <= 0.06 rad/s, moving on both sides)."""
    t_grasp, t_release = instants(plan)
    k0, k1 = index(plan, t_grasp) + 26, index(plan, t_release) - 1
    speed = np.abs(velocity(plan)).max(axis=1)
    moving = moving_mask(plan)
    return [
        k
        for k in range(k0, k1)
        if speed[k - 1] <= 0.06
        and speed[k] <= 0.06
        and moving[k - 1]
        and moving[k]
        and speed[k - 1] + speed[k] <= min(speed[k - 2], speed[k + 1])
    ]
