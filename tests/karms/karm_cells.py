"""Cells of one, three and four UR5e arms around a 1.2 m x 1.0 m table (``data/*.yaml``: south,
north, west and east of the table) and hand-made plans for them (no planner: each plan is a list
of phases, built into a plan file by :func:`~sdar_tamp.plan_building.build_plan_file`).

A phase is either motion (``{arm: target configuration}``: the named arms go there together,
on a cosine profile timed by the largest joint step, the others stand still) or gripper events
(a list of :class:`~sdar_tamp.plan_building.GripperEvent`, simultaneous). :func:`pick_place`
makes every named arm carry its object from its start to its goal at once: above the start,
down, grasp, up, above the goal, down, release, up, home.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from sdar_tamp.plan_building import GripperEvent, MotionSegment, build_plan_file
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.world.instance import Instance, ObjectSpec, Pose2D
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene, load_scene
from sdar_tamp.world.transforms import FloatArray, inverse, pose_xyz_yaw

DATA = Path(__file__).with_name("data")
CELLS = {1: "one_arm.yaml", 3: "three_arms.yaml", 4: "four_arms.yaml"}
SIZE = (0.08, 0.04, 0.05)
#: The object in the tool-centre-point frame: tool z down, the fingers (tool y) closing along
#: the object's short side (its y), the TCP at the object's centre.
T_TCP_OBJ = np.diag([-1.0, 1.0, -1.0, 1.0])
ABOVE = 0.10  #: [m] the tool's height above a grasp or release pose on the way in and out
DT = 0.02
V_SHARE, A_SHARE = 0.5, 0.5  #: share of the joint limits the cosine profiles use

Move = Mapping[str, FloatArray]
Phase = Move | Sequence[GripperEvent]


def cell(k: int) -> Scene:
    """The test cell of ``k`` arms (1, 3 or 4)."""
    return load_scene(DATA / CELLS[k])


def object_pose(x: float, y: float, yaw: float, dz: float = 0.0) -> FloatArray:
    return pose_xyz_yaw(x, y, SIZE[2] / 2 + dz, yaw)


def ik(scene: Scene, arm: str, T_world_tcp: FloatArray, q_ref: FloatArray) -> FloatArray:
    """The arm's configuration nearest to ``q_ref`` with its TCP at ``T_world_tcp``."""
    q, ok = ArmKinematics.from_scene(scene, arm).ik_tcp(T_world_tcp[None]).closest(q_ref)
    assert ok[0], f"{arm}: no IK for {T_world_tcp[:3, 3]}"
    return q[0]


def tool_at(scene: Scene, arm: str, pose: tuple[float, float, float], dz: float, q_ref: FloatArray):
    """The arm holding (or about to hold) an object at ``pose`` lifted by ``dz`` [m]."""
    return ik(scene, arm, object_pose(*pose, dz=dz) @ inverse(T_TCP_OBJ), q_ref)


def cosine(q0: FloatArray, q1: FloatArray, scene: Scene, arms: Sequence[str]) -> MotionSegment:
    """Every arm from ``q0`` to ``q1`` (full configurations) on one cosine profile, as slow as
    the arm that needs longest at ``V_SHARE`` / ``A_SHARE`` of its limits."""
    step = np.abs(q1 - q0)
    v = scene.joint_array("velocity_limit") * V_SHARE
    a = scene.joint_array("acceleration_limit") * A_SHARE
    # cosine profile over T: peak speed pi A / 2T, peak acceleration pi^2 A / 2T^2
    need = max(
        float(np.max(math.pi * step / (2 * v))), float(np.max(np.sqrt(math.pi**2 * step / (2 * a))))
    )
    n = max(2, math.ceil(need / DT))
    s = 0.5 - 0.5 * np.cos(np.pi * np.arange(n + 1) / n)
    return MotionSegment(
        np.arange(n + 1) * DT, q0 + s[:, None] * (q1 - q0), "plain", tuple(arms), "move"
    )


def build(
    scene: Scene, instance: Instance, phases: Sequence[Phase], name: str | None = None
) -> PlanFile:
    """The plan file of ``phases`` (see the module docstring) on ``instance``."""
    layout = scene.layout
    q = scene.home.copy()
    items: list[MotionSegment | GripperEvent] = []
    for phase in phases:
        if isinstance(phase, Mapping):
            q1 = q.copy()
            for arm, target in phase.items():
                q1[layout.slice(arm)] = target
            items.append(cosine(q, q1, scene, list(phase)))
            q = q1
        else:
            items.extend(phase)
    return build_plan_file(
        scene,
        name or instance.name,
        {o.name: o.start.as_tuple() for o in instance.objects},
        {o.name: o.size for o in instance.objects},
        items,
        {"task_planner": "by hand"},
    )


def pick_place(scene: Scene, moves: Mapping[str, tuple[str, Pose2D, Pose2D]]) -> list[Phase]:
    """Phases in which every arm of ``moves`` (arm -> object, start, goal) carries its object
    at once; the arms' gripper events are simultaneous."""
    home = {a: np.array(scene.arm(a).home) for a in moves}
    starts = {a: m[1].as_tuple() for a, m in moves.items()}
    goals = {a: m[2].as_tuple() for a, m in moves.items()}
    above_start = {a: tool_at(scene, a, starts[a], ABOVE, home[a]) for a in moves}
    at_start = {a: tool_at(scene, a, starts[a], 0.0, above_start[a]) for a in moves}
    above_goal = {a: tool_at(scene, a, goals[a], ABOVE, above_start[a]) for a in moves}
    at_goal = {a: tool_at(scene, a, goals[a], 0.0, above_goal[a]) for a in moves}
    grasp = [GripperEvent(a, "grasp", m[0], T_TCP_OBJ) for a, m in moves.items()]
    release = [GripperEvent(a, "release", m[0], T_TCP_OBJ) for a, m in moves.items()]
    return [
        above_start,
        at_start,
        grasp,
        above_start,
        above_goal,
        at_goal,
        release,
        above_goal,
        home,
    ]


def instance_of(
    name: str, scene: Scene, moves: Mapping[str, tuple[str, Pose2D, Pose2D]]
) -> Instance:
    objects = tuple(ObjectSpec(m[0], SIZE, m[1], m[2]) for m in moves.values())
    return Instance(name, scene.workspace, objects)


#: Every arm carries an object towards the middle of the table, where the grippers end up
#: a few centimetres apart (``gap`` [m]: between the south and north objects' centres).
def crossing(k: int, gap: float = 0.16) -> dict[str, tuple[str, Pose2D, Pose2D]]:
    half = math.pi / 2
    moves = {
        "south": ("s1", Pose2D(-0.2, -0.2, 0.0), Pose2D(0.0, -gap / 2, 0.0)),
        "north": ("n1", Pose2D(0.2, 0.2, 0.0), Pose2D(0.0, gap / 2, 0.0)),
        "west": ("w1", Pose2D(-0.26, 0.15, half), Pose2D(-0.12, 0.0, half)),
        "east": ("e1", Pose2D(0.26, -0.15, half), Pose2D(0.12, 0.0, half)),
    }
    return dict(list(moves.items())[:k])


def relay(scene: Scene) -> tuple[Instance, list[Phase]]:
    """The west arm carries ``o1`` to the middle of the table and goes home; then the east
    arm takes it from there to the east (one arm moving at a time; the others stand still)."""
    start, middle, goal = (-0.24, 0.1, 0.0), (0.0, 0.0, 0.0), (0.24, -0.1, 0.0)
    obj = ObjectSpec("o1", SIZE, Pose2D(*start), Pose2D(*goal))
    instance = Instance("relay", scene.workspace, (obj,))
    phases: list[Phase] = []
    for arm, a, b in (("west", start, middle), ("east", middle, goal)):
        home = np.array(scene.arm(arm).home)
        above_a = tool_at(scene, arm, a, ABOVE, home)
        at_a = tool_at(scene, arm, a, 0.0, above_a)
        above_b = tool_at(scene, arm, b, ABOVE, above_a)
        at_b = tool_at(scene, arm, b, 0.0, above_b)
        phases += [{arm: above_a}, {arm: at_a}, [GripperEvent(arm, "grasp", "o1", T_TCP_OBJ)]]
        phases += [{arm: above_a}, {arm: above_b}, {arm: at_b}]
        phases += [[GripperEvent(arm, "release", "o1", T_TCP_OBJ)], {arm: above_b}, {arm: home}]
    return instance, phases


def shifted(plan: PlanFile, arm: str, ticks: int) -> PlanFile:
    """``plan`` with ``arm``'s joints and gripper events ``ticks`` samples earlier (its motion
    unchanged, only started sooner; it stands at its last configuration at the end). The
    plan's samples must be uniform."""
    cols = plan.layout.slice(arm)
    q = plan.q.copy()
    q[:-ticks, cols] = plan.q[ticks:, cols]
    q[-ticks:, cols] = plan.q[-1, cols]
    step = float(plan.t[1] - plan.t[0])
    events = sorted(
        (
            dataclasses.replace(e, t=round(e.t - ticks * step, 9)) if e.arm == arm else e
            for e in plan.events
        ),
        key=lambda e: e.t,
    )
    return dataclasses.replace(plan, q=q, events=tuple(events))
