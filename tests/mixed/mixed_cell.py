"""A cell of two arms with different joint counts: the shipped cell's left UR5e (6 joints) beside
a 7-joint arm (``panda_arm.urdf``: the Franka Panda's published joint placements and limits),
and a hand-made plan for it (no planner: the records are built directly).

The 7-joint arm is an :class:`~sdar_tamp.world.scene.ArmSpec` that names its joints and its
robot description (``joint_names``, ``urdf``), as the cell files do that give every arm its own
robot; :func:`seven_joint_arm` is the one place that builds it.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from sdar_tamp.plan_file import ArmInfo, PlanEvent, PlanFile, StepRecord, plan_joint_names
from sdar_tamp.plan_metrics import PlanMetrics
from sdar_tamp.world.instance import ObjectSpec, Pose2D
from sdar_tamp.world.scene import ArmSpec, Scene, load_scene
from sdar_tamp.world.transforms import FloatArray, pose_xyz_yaw, translation

PANDA_URDF = Path(__file__).with_name("panda_arm.urdf")
PANDA_JOINTS = tuple(f"panda_joint{i}" for i in range(1, 8))
PANDA_LOWER = (-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973)
PANDA_UPPER = (2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973)
PANDA_VELOCITY = (2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61)
PANDA_ACCELERATION = (15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0)
PANDA_HOME = (0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785)
SIZE = (0.08, 0.04, 0.05)
OBJECTS = (
    ObjectSpec("o1", SIZE, Pose2D(-0.1, 0.1, 0.0), Pose2D(-0.1, -0.1, 0.0)),
    ObjectSpec("o2", SIZE, Pose2D(0.1, -0.1, 0.0), Pose2D(0.1, 0.1, 0.0)),
)
T_TCP_OBJ = pose_xyz_yaw(0.0, 0.0, 0.01, 0.0)
DT = 0.02


def seven_joint_arm(like: ArmSpec) -> ArmSpec:
    """A 7-joint arm at ``like``'s base pose, with ``like``'s gripper."""
    return dataclasses.replace(
        like,
        urdf=PANDA_URDF,
        base_frame="panda_link0",
        tool_frame="tool0",
        joint_names=PANDA_JOINTS,
        lower=PANDA_LOWER,
        upper=PANDA_UPPER,
        velocity_limit=PANDA_VELOCITY,
        acceleration_limit=PANDA_ACCELERATION,
        home=PANDA_HOME,
        locked_joints=(),
    )


def mixed_cell() -> Scene:
    """The shipped cell with its right arm replaced by the 7-joint arm."""
    scene = load_scene()
    left, right = scene.arms
    return dataclasses.replace(scene, arms=(left, seven_joint_arm(right)))


def rest_to_rest(q0: FloatArray, q1: FloatArray, n: int) -> FloatArray:
    """``n + 1`` samples ``DT`` apart from ``q0`` to ``q1``, starting and ending at rest."""
    s = 0.5 - 0.5 * np.cos(np.pi * np.arange(n + 1) / n)
    return q0 + s[:, None] * (q1 - q0)


def mixed_plan(scene: Scene) -> PlanFile:
    """Both arms move at once (the left for 1 s, the right for 1.4 s); the left grasps o1 at
    1.0 s, the right o2 at 1.4 s; each arm stands still 0.5 s after its event; 0.5 s at rest
    at the end."""
    layout = scene.layout
    home = scene.home
    left_goal = layout.part(home, "left") + np.array([0.3, -0.2, 0.25, 0.1, -0.15, 0.4])
    right_goal = layout.part(home, "right") + np.array([0.4, 0.3, -0.2, 0.3, 0.25, -0.3, 0.5])
    n = round(2.4 / DT)
    left = np.repeat(left_goal[None], n + 1, axis=0)
    left[:51] = rest_to_rest(layout.part(home, "left"), left_goal, 50)
    right = np.repeat(right_goal[None], n + 1, axis=0)
    right[:71] = rest_to_rest(layout.part(home, "right"), right_goal, 70)
    q = layout.join({"left": left, "right": right})
    t = np.arange(n + 1) * DT
    arms = tuple(
        ArmInfo(
            a.name,
            plan_joint_names(a.name, a.joint_names),
            a.T_world_base,
            translation(0.0, 0.0, a.gripper.tcp_offset),
            np.array(a.home),
        )
        for a in scene.arms
    )
    events = (
        PlanEvent(1.0, "left", "grasp", "o1", T_TCP_OBJ),
        PlanEvent(1.4, "right", "grasp", "o2", T_TCP_OBJ),
    )
    steps = (StepRecord(0.0, 1.4, "plain", ("o1", "o2"), "pick"),)
    finals = {"o1": (-0.1, 0.1, 0.0), "o2": (0.1, -0.1, 0.0)}
    metrics = PlanMetrics.from_mapping(
        {"actions": 0, "steps": 1, "dual_arm_steps": 1, "execution_time": float(t[-1])}
    )
    return PlanFile("X2", arms, t, q, events, finals, metrics, steps)
