"""Independent validation of a plan file by replaying it against an instance.

Shares no code with the planner (``streams/``): it uses only the world model (scene,
kinematics, the coal collision world, footprints) and the plan format. The rules that need no
replay (format, scene, instance, joint limits, velocity, acceleration, dwell) are in
:mod:`sdar_tamp.plan_rules`; the replay walks the timeline once, in time order, up to the
earliest of those violations, and returns the FIRST violation. Replay rules:

* ``collision``: samples are linearly interpolated in joint space so that no tool centre point
  moves more than ``max_tcp_step`` [m] between checks (refined until true); each check is a
  :class:`CollisionWorld` query: arm-arm, self, arm-table, arm-objects, held objects against
  everything except their own wrist and gripper (objects shrunk by 1 mm). At an event instant
  the configuration is checked before and after the gripper changes. Contact rule: the
  gripper of an arm may touch the object of its grasp or release only while that arm stands
  exactly at its configuration of the event (the event sample and the dwell after it);
  once the arm moves, every contact counts.
* ``grasp``: by an empty gripper, of a resting object, with ``T_world_tcp @ T_tcp_object``
  equal to the object's resting pose within 1 mm and 1 degree (modulo the cuboid's symmetry).
  The object is then held rigidly where it really was relative to the tool.
* ``release``: by the arm holding the object, ``T_tcp_object`` as held (1 mm, 1 degree); the
  object must rest flat (z = lz/2 within 1 mm, its z axis vertical within 1 degree), with its
  footprint inside the instance workspace (1 mm) and not overlapping any resting object's
  footprint (the released footprint is shrunk by 1 mm per side).
* at the end: ``held`` (nothing in hand), ``goal`` (every object at its goal within 1 mm and
  1 degree, yaw modulo pi), ``final poses`` (equal to the plan's ``final_poses``, same
  tolerances).

The walk itself is :class:`~sdar_tamp.replay_walk.ReplayWalk`; the points it checks between
samples come from :mod:`sdar_tamp.replay_sampling`. The README section "What `sdar validate`
checks" lists every rule with its tolerance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import GRIPPER_DWELL, PlanFile
from sdar_tamp.plan_rules import (
    LIMIT_RTOL,
    Violation,
    check_format,
    check_instance,
    check_scene,
    check_timeline,
)
from sdar_tamp.replay_walk import ReplayWalk
from sdar_tamp.world.collision import CollisionWorld
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene, load_scene

__all__ = ["PlanValidator", "ReplayReport", "Violation", "validate_plan"]


@dataclass(frozen=True)
class ReplayReport:
    """``ok`` or the first violation; ``checks`` counts the collision queries made."""

    ok: bool
    violation: Violation | None
    checks: int


class PlanValidator:
    """Validates plans against one scene; the kinematics and collision geometry are built
    once (about 50 ms) and reused by every :meth:`validate` call.

    ``max_tcp_step`` [m]: largest tool-centre-point travel between collision checks;
    ``dwell`` [s]: still time after gripper events; ``velocity_tolerance`` and
    ``acceleration_tolerance``: relative tolerances of the limits (numerical, 1e-6).
    """

    def __init__(
        self,
        scene: Scene,
        max_tcp_step: float = 0.005,
        *,
        dwell: float = GRIPPER_DWELL,
        velocity_tolerance: float = LIMIT_RTOL,
        acceleration_tolerance: float = LIMIT_RTOL,
    ) -> None:
        for name, value, ok in (
            ("max_tcp_step", max_tcp_step, max_tcp_step > 0.0),
            ("dwell", dwell, dwell >= 0.0),
            ("velocity_tolerance", velocity_tolerance, velocity_tolerance >= 0.0),
            ("acceleration_tolerance", acceleration_tolerance, acceleration_tolerance >= 0.0),
        ):
            if not (ok and math.isfinite(value)):
                raise ParameterError(
                    f"{name}: expected a finite number >= 0 (> 0 for max_tcp_step), got {value!r}"
                )
        self.scene, self.step, self.dwell = scene, max_tcp_step, dwell
        self.v_tol, self.a_tol = velocity_tolerance, acceleration_tolerance
        self.kins = {a: ArmKinematics.from_scene(scene, a) for a in scene.arm_names}
        # the replay builds each arrangement's geometry afresh: it does not rely on the
        # planner's in-place updates (collision_slots) that it is there to check
        self.world = CollisionWorld(scene, incremental=False)

    def validate(self, instance: Instance, plan: PlanFile) -> ReplayReport:
        """Replay ``plan`` on ``instance``: ok, or the first violation in time."""
        first = (
            check_format(plan) or check_scene(plan, self.scene) or check_instance(plan, instance)
        )
        if first is not None:
            return ReplayReport(False, first, 0)
        limit = check_timeline(plan, self.scene, self.dwell, self.v_tol, self.a_tol)
        if limit is not None and limit.t <= 0.0:
            return ReplayReport(False, limit, 0)
        for arm in self.scene.arm_names:  # a fresh world: nothing held
            if self.world.held_by(arm) is not None:
                self.world.detach(arm)
        replay = ReplayWalk(instance, plan, self.scene, self.step, self.kins, self.world)
        found = replay.walk(limit.t if limit is not None else math.inf)
        violation = found if found is not None else limit
        return ReplayReport(violation is None, violation, replay.checks)


def validate_plan(
    instance: Instance,
    plan: PlanFile,
    scene: Scene | None = None,
    max_tcp_step: float = 0.005,
    *,
    dwell: float = GRIPPER_DWELL,
    velocity_tolerance: float = LIMIT_RTOL,
    acceleration_tolerance: float = LIMIT_RTOL,
) -> ReplayReport:
    """Replay ``plan`` on ``instance`` (default scene: the instance's, else the shipped one);
    see :class:`PlanValidator` for the parameters."""
    scene = scene if scene is not None else load_scene(instance.scene_path())
    validator = PlanValidator(
        scene,
        max_tcp_step,
        dwell=dwell,
        velocity_tolerance=velocity_tolerance,
        acceleration_tolerance=acceleration_tolerance,
    )
    return validator.validate(instance, plan)
