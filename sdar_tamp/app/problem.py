"""How an instance becomes a problem: the rearrangement domain, its init facts and its streams.

:func:`rearrangement_problem` turns an :class:`~sdar_tamp.world.instance.Instance` into a
:class:`~sdar_tamp.language.problem.PDDLProblem` of ``domains/dual_arm_rearrangement`` (init
facts over Python values, the goal, the stream map of :mod:`streams.stream_map`), configured
by a :class:`~sdar_tamp.app.config.PlannerConfig`. The cell may have any number of arms: the
initial cell configuration holds one ``confin`` fact per arm, and ``combine-confs`` is
declared for the cell's arms (:func:`~sdar_tamp.app.cell_streams.streams_for_arms`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from sdar_tamp.app.cell_streams import streams_for_arms
from sdar_tamp.app.config import MOTION_PLANNERS, PlannerConfig, check_choice
from sdar_tamp.errors import ParameterError
from sdar_tamp.language.generators import from_gen_fn, from_test
from sdar_tamp.language.problem import PDDLProblem
from sdar_tamp.logs import get_logger
from sdar_tamp.resources import domain_file
from sdar_tamp.world.instance import Instance, Pose2D
from solvers.sdar.options import Plane
from streams.context import WorldContext
from streams.grasps import sample_grasps
from streams.motion.planner import MotionPlanner
from streams.stream_map import make_stream_map
from streams.stream_types import STREAM_KINDS, ArmConf, CellConf

DOMAIN = "dual_arm_rearrangement"
LOG = get_logger(__name__)


@dataclass(frozen=True)
class Rearrangement:
    """An instance as a planning problem, with the world it lives in and its configuration."""

    instance: Instance
    ctx: WorldContext
    problem: PDDLProblem
    home: CellConf
    config: PlannerConfig = field(default_factory=PlannerConfig)
    start: CellConf | None = None  # where the arms begin (None: at home)

    @property
    def start_conf(self) -> CellConf:
        """Where the arms begin: ``start``, else ``home``."""
        return self.start if self.start is not None else self.home

    @property
    def motion(self) -> str:
        """The motion planner behind ``plan-dual-motion`` (``config.motion_planner``)."""
        return self.config.motion_planner


def _wrap(kind: str, fn: Callable[..., Any]) -> Callable[..., Any]:
    if kind == "gen":
        return from_gen_fn(fn)
    if kind == "test":
        return from_test(fn)
    return fn  # functions are called as they are


def rearrangement_problem(
    instance: Instance,
    ctx: WorldContext | None = None,
    *,
    config: PlannerConfig | None = None,
    seed: int | None = None,
    motion: str | None = None,
    planner: MotionPlanner | None = None,
    gripper_time: float | None = None,
    overrides: Mapping[str, Callable[..., Any]] | None = None,
    start: CellConf | None = None,
) -> Rearrangement:
    """The PDDLProblem of ``instance`` (see the module docstring).

    ``config``: the planner configuration (default: :class:`PlannerConfig`); ``seed``,
    ``motion`` (its ``motion_planner``) and ``gripper_time`` [s], when given, replace its
    fields. ``planner``: a motion planner to share between problems (its optimiser takes a
    few tenths of a second to build; default: a new one with ``config.trajopt``).
    ``overrides``: stream name -> plain callable replacing the shipped stream (same signature
    and kind as in :mod:`streams.stream_map`). ``start``: the arms' configuration to begin
    from (default: home; idle arms still wait at home), with empty grippers.

    Raises:
        ParameterError: a value out of range, an unknown motion planner or stream name.
    """
    if motion is not None:
        check_choice("motion", motion, MOTION_PLANNERS)
    config = (config or PlannerConfig()).replace(
        seed=seed, motion_planner=motion, gripper_time=gripper_time
    )
    ctx = ctx or WorldContext.load()
    planner = planner if planner is not None else MotionPlanner(ctx, config.trajopt)
    sizes = {o.name: o.size for o in instance.objects}
    goals = {o.name: o.goal for o in instance.objects}
    stream_map = make_stream_map(
        ctx, sizes, config.seed, planner, goals, config.motion_planner, config.grasps
    )
    unknown = sorted(set(overrides or {}) - set(stream_map))
    if unknown:
        raise ParameterError(f"overrides: unknown streams {unknown}; known: {sorted(stream_map)}")
    stream_map.update(overrides or {})
    _note_grasp_cut(instance, ctx, config)
    wrapped = {name: _wrap(STREAM_KINDS[name], fn) for name, fn in stream_map.items()}
    arms = ctx.arm_names
    confs = {a: ArmConf(a, tuple(float(x) for x in ctx.home(a))) for a in arms}
    home = CellConf(*(confs[a] for a in arms))
    begin = home if start is None or start == home else start
    init: list[tuple[Any, ...]] = [("dualconf", home), ("atdualconf", begin)]
    init.append(("=", ("gripper-time",), float(config.gripper_time)))
    for a in arms:
        init += [("arm", a), ("empty", a), ("armconf", confs[a]), ("confof", a, confs[a])]
        init.append(("confin", home, a, confs[a]))
    if begin is not home:
        init.append(("dualconf", begin))
        for a in arms:
            conf = begin.arm(a)
            init += [("armconf", conf), ("confof", a, conf), ("confin", begin, a, conf)]
    options = dataclasses.replace(config.sdar_options(), plane=table_plane(ctx))
    if begin is not home:
        options = dataclasses.replace(options, home=home)
    for o in instance.objects:
        init += [("obj", o.name), ("pose", o.start), ("pose", o.goal)]
        init += [("objpose", o.name, o.start), ("objpose", o.name, o.goal)]
        init.append(("atpose", o.name, o.start))
    goal = ("and", *(("atpose", o.name, o.goal) for o in instance.objects))
    problem = PDDLProblem(
        domain_file(DOMAIN).read_text(encoding="utf-8"),
        {},
        streams_for_arms(domain_file(DOMAIN, "stream.pddl").read_text(encoding="utf-8"), len(arms)),
        wrapped,
        init,
        goal,
        solve_defaults={
            "task_planner": config.task_planner,
            "sdar_options": options,
        },
    )
    return Rearrangement(instance, ctx, problem, home, config, None if begin is home else begin)


def table_plane(ctx: WorldContext) -> Plane:
    """Where poses lie on the table for SDAR-T's steps of more than two moves: a pose's
    ``(x, y)``, the arms' base positions (:class:`solvers.sdar.options.Plane`)."""
    bases = {
        a: (float(ctx.scene.arm(a).base_xyz[0]), float(ctx.scene.arm(a).base_xyz[1]))
        for a in ctx.arm_names
    }
    return Plane(_plane_xy, bases)


def _plane_xy(value: object) -> tuple[float, float] | None:
    return (value.x, value.y) if isinstance(value, Pose2D) else None


def grasp_set_sizes(instance: Instance, ctx: WorldContext, config: PlannerConfig) -> dict[str, int]:
    """Object name -> number of grasps in its grasp set (``config.grasps``)."""
    limits = ctx.scene.grasp_limits
    return {
        o.name: len(sample_grasps(o.size, limits, config.grasps.tilts, config.grasps.symmetric))
        for o in instance.objects
    }


def _note_grasp_cut(instance: Instance, ctx: WorldContext, config: PlannerConfig) -> None:
    """Log (INFO) when SDAR-M tries fewer grasps per object than the grasp set holds."""
    sizes = grasp_set_sizes(instance, ctx, config)
    tried = config.sdar.grasps
    cut = {name: n for name, n in sizes.items() if n > tried}
    if cut:
        LOG.info(
            "%s: SDAR-M tries the first %d grasps of each object (PlannerConfig.sdar.grasps); "
            "the grasp set holds up to %d for %d object(s)",
            instance.name,
            tried,
            max(cut.values()),
            len(cut),
        )
