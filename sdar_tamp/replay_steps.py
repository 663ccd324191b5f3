"""The replay of a plan while it is being planned: each new stretch of the timeline checked
before it is executed.

:class:`StepValidator` keeps the state of the independent replay (:mod:`sdar_tamp.replay`:
resting and held objects, the collision world, the contact rule's exemptions) between
stretches. Each stretch, the samples and gripper events a planner has just fixed, is checked
against the world as it is then, by the rules that apply to a stretch on its own: joint limits
and velocities (:func:`~sdar_tamp.plan_rules.check_samples`), collisions along the motions
and the gripper events (:meth:`~sdar_tamp.replay_walk.ReplayWalk.walk_samples`), from the last
sample of the stretch before. :meth:`StepValidator.finish` adds the end rules (nothing held,
every object at its goal). What needs the whole timeline (the plan file's format, the
accelerations at the seams, the dwell before the next motion, the plan's ``final_poses``) is
left to :func:`~sdar_tamp.replay.validate_plan` on the finished plan.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import PlanEvent
from sdar_tamp.plan_rules import LIMIT_RTOL, Violation, check_samples
from sdar_tamp.replay_walk import ReplayWalk
from sdar_tamp.world.collision import CollisionWorld
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray


class StepValidator:
    """Checks a timeline stretch by stretch on ``instance`` in ``scene``; see the module
    docstring. ``max_tcp_step`` [m] and ``velocity_tolerance`` as in
    :class:`~sdar_tamp.replay.PlanValidator`."""

    def __init__(
        self,
        instance: Instance,
        scene: Scene,
        max_tcp_step: float = 0.005,
        velocity_tolerance: float = LIMIT_RTOL,
    ) -> None:
        if not max_tcp_step > 0.0:
            raise ParameterError(f"max_tcp_step: expected a number > 0 [m], got {max_tcp_step!r}")
        self.scene, self.v_tol = scene, velocity_tolerance
        kins = {a: ArmKinematics.from_scene(scene, a) for a in scene.arm_names}
        world = CollisionWorld(scene, incremental=False)  # built afresh, as in replay.py
        self.walk = ReplayWalk(instance, None, scene, max_tcp_step, kins, world)
        self._last: tuple[FloatArray, FloatArray] | None = None  # the last sample checked
        self.failed: Violation | None = None

    def check(self, t: FloatArray, q: FloatArray, events: Sequence[PlanEvent]) -> Violation | None:
        """Check the next stretch: samples ``q`` ``(n, dof)`` [rad] at ``t`` ``(n,)`` [s]
        (the first stretch from ``t = 0``; each next one after the last sample of the one
        before) and its gripper events. Returns the first violation, or None; after a
        violation every stretch is refused with it.

        Raises:
            ParameterError: samples of the wrong shape, or not after the stretch before.
        """
        if self.failed is not None:
            return self.failed
        t = np.asarray(t, dtype=np.float64)
        q = np.asarray(q, dtype=np.float64)
        dof = self.scene.layout.dof
        if t.ndim != 1 or q.shape != (len(t), dof):
            raise ParameterError(
                f"a stretch needs t (n,) and q (n, {dof}); got {t.shape} and {q.shape}"
            )
        if self._last is not None:
            if len(t) and t[0] <= self._last[0][0]:
                raise ParameterError(
                    f"the stretch starts at t = {t[0]:.3f} s, not after the last one checked "
                    f"(t = {self._last[0][0]:.3f} s)"
                )
            t, q = np.append(self._last[0], t), np.vstack([self._last[1], q])
        elif not len(t) or t[0] != 0.0:
            raise ParameterError("the first stretch starts with the sample at t = 0")
        found = check_samples(t, q, self.scene, self.v_tol) or self.walk.walk_samples(t, q, events)
        self._last = (t[-1:], q[-1:])
        self.failed = found
        return found

    def finish(self) -> Violation | None:
        """The end rules once the last stretch is checked: nothing held, every object at its
        goal (or the violation met before)."""
        if self.failed is not None or self._last is None:
            return self.failed
        return self.walk.final(float(self._last[0][0]))
