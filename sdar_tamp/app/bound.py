"""The execution-time lower bound of an instance with the planner's grasp set.

:mod:`sdar_tamp.world.execution_bound` computes the bound from any grasp set; this module
gives it the planner's (the configuration's :class:`~streams.grasps.GraspOptions`, pair
tilts included: a larger set only lowers the minimum, so the bound holds for every grasp the
planner may use) and its gripper dwell (``PlannerConfig.gripper_time``).
"""

from __future__ import annotations

from sdar_tamp.app.config import PlannerConfig
from sdar_tamp.world.execution_bound import ExecutionBound, execution_bound
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene
from streams.grasps import sample_grasps


def instance_bound(
    scene: Scene, instance: Instance, config: PlannerConfig | None = None
) -> ExecutionBound:
    """The lower bound on the execution time [s] of any plan of ``instance`` in ``scene``
    under ``config``'s grasp set and gripper dwell (default :class:`PlannerConfig`)."""
    cfg = config or PlannerConfig()
    options = cfg.grasps
    limits = scene.grasp_limits
    grasps = {
        o.name: tuple(
            g.T_object_tcp
            for g in sample_grasps(
                o.size, limits, options.tilts, options.symmetric, pair_tilts=options.pair_tilts
            )
        )
        for o in instance.objects
    }
    return execution_bound(scene, instance, grasps, cfg.gripper_time)
