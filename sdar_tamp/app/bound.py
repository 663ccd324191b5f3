"""The execution-time lower bound of an instance with the planner's grasp set.

:mod:`sdar_tamp.world.execution_bound` computes the bound from any grasp set; this module
gives it the planner's (the configuration's :class:`~streams.grasps.GraspOptions`, pair
tilts included: a larger set only lowers the minimum, so the bound holds for every grasp the
planner may use) and its gripper dwell (``PlannerConfig.gripper_time``).

:func:`run_bound`, the pipeline's, computes it only where it is proven: when every arm of the
cell has the closed-form IK. For an arm solved by the numeric IK the minimum would run over
the branches the numeric IK happens to find (no proof), and finding them for every grasp of
every object at both ends takes tens of seconds (a Panda cell, 12 objects: 29 s), so a run
in such a cell reports no bound.
"""

from __future__ import annotations

from collections.abc import Mapping

from sdar_tamp.app.config import PlannerConfig
from sdar_tamp.world.execution_bound import ExecutionBound, execution_bound
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene
from streams.context import WorldContext
from streams.grasps import sample_grasps


def run_bound(
    ctx: WorldContext, instance: Instance, config: PlannerConfig
) -> ExecutionBound | None:
    """The bound of ``instance`` in the world ``ctx`` (its arms' kinematics reused), or
    ``None`` when an arm has no closed-form IK (see the module docstring)."""
    if not all(k.closed_form for k in ctx.kinematics.values()):
        return None
    return instance_bound(ctx.scene, instance, config, ctx.kinematics)


def instance_bound(
    scene: Scene,
    instance: Instance,
    config: PlannerConfig | None = None,
    kinematics: Mapping[str, ArmKinematics] | None = None,
) -> ExecutionBound:
    """The lower bound on the execution time [s] of any plan of ``instance`` in ``scene``
    under ``config``'s grasp set and gripper dwell (default :class:`PlannerConfig`);
    ``kinematics``: the arms' (default: loaded from the scene)."""
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
    return execution_bound(scene, instance, grasps, cfg.gripper_time, kinematics)
