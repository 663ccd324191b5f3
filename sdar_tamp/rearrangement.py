"""Wiring of a rearrangement instance: the dual-arm domain, its streams and the solver.

:func:`rearrangement_problem` turns an :class:`~sdar_tamp.world.instance.Instance` into a
:class:`~sdar_tamp.language.problem.PDDLProblem` of ``domains/dual_arm_rearrangement`` (init
facts over Python values, the goal, the stream map of :mod:`streams.stream_map`);
:func:`solve_instance` runs a solver on it and returns the solution with the timeline that the
plan file (:mod:`sdar_tamp.plan_file`) is built from.
This is the one module that wires the language, the solvers and the geometric streams.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from sdar_tamp.arguments import MAX_TIME, SEED, Real
from sdar_tamp.errors import ParameterError
from sdar_tamp.language.generators import from_gen_fn, from_test
from sdar_tamp.language.problem import PDDLProblem
from sdar_tamp.plan_file import (
    GRIPPER_DWELL,
    GripperEvent,
    MotionSegment,
    PlanFile,
    build_plan_file,
)
from sdar_tamp.resources import domain_file
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.transforms import inverse
from solvers.solution import Action, Solution
from streams.context import WorldContext
from streams.motion import DualMotionPlanner, MotionResult
from streams.stream_map import STREAM_KINDS, ArmConf, DualConf, make_stream_map

DOMAIN = "dual_arm_rearrangement"
TASK_PLANNERS = ("sdar", "baseline")
MOTION_PLANNERS = ("sdar", "plain", "sequential")
GRIPPER_TIME = GRIPPER_DWELL  # [s] one gripper action (both grippers at once take as long)
_DURATION = Real(0.0, closed=True, unit="s")  # gripper_time


@dataclass(frozen=True)
class Rearrangement:
    """An instance as a planning problem, with the world it lives in."""

    instance: Instance
    ctx: WorldContext
    problem: PDDLProblem
    home: DualConf
    motion: str = "sdar"  # the motion planner behind plan-dual-motion (MOTION_PLANNERS)


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
    seed: int = 0,
    motion: str = "sdar",
    planner: DualMotionPlanner | None = None,
    gripper_time: float = GRIPPER_TIME,
    overrides: Mapping[str, Callable[..., Any]] | None = None,
) -> Rearrangement:
    """The PDDLProblem of ``instance`` (see the module docstring).

    ``overrides``: stream name -> plain callable replacing the shipped stream (same
    signature and kind as in :mod:`streams.stream_map`).

    ``motion``: the motion planner behind ``plan-dual-motion``, one of
    :data:`MOTION_PLANNERS`; ``planner``: a motion planner to share between problems (its
    optimiser takes a few seconds to build).
    """
    if motion not in MOTION_PLANNERS:
        raise ParameterError(
            f"motion planner must be one of {', '.join(MOTION_PLANNERS)}; got {motion!r}"
        )
    seed = SEED.check("seed", seed)
    gripper_time = _DURATION.check("gripper_time", gripper_time)
    ctx = ctx or WorldContext.load()
    sizes = {o.name: o.size for o in instance.objects}
    goals = {o.name: o.goal for o in instance.objects}
    stream_map = make_stream_map(ctx, sizes, seed, planner, goals, motion)
    unknown = sorted(set(overrides or {}) - set(stream_map))
    if unknown:
        raise ParameterError(f"overrides: unknown streams {unknown}; known: {sorted(stream_map)}")
    stream_map.update(overrides or {})
    wrapped = {name: _wrap(STREAM_KINDS[name], fn) for name, fn in stream_map.items()}
    arms = ctx.arm_names
    confs = {a: ArmConf(a, tuple(float(x) for x in ctx.home(a))) for a in arms}
    home = DualConf(confs[arms[0]], confs[arms[1]])
    init: list[tuple[Any, ...]] = [("dualconf", home), ("atdualconf", home)]
    init.append(("=", ("gripper-time",), float(gripper_time)))
    for a in arms:
        init += [("arm", a), ("empty", a), ("armconf", confs[a]), ("confof", a, confs[a])]
        init.append(("confin", home, a, confs[a]))
    for o in instance.objects:
        init += [("obj", o.name), ("pose", o.start), ("pose", o.goal)]
        init += [("objpose", o.name, o.start), ("objpose", o.name, o.goal)]
        init.append(("atpose", o.name, o.start))
    goal = ("and", *(("atpose", o.name, o.goal) for o in instance.objects))
    problem = PDDLProblem(
        domain_file(DOMAIN).read_text(encoding="utf-8"),
        {},
        domain_file(DOMAIN, "stream.pddl").read_text(encoding="utf-8"),
        wrapped,
        init,
        goal,
    )
    return Rearrangement(instance, ctx, problem, home, motion)


# -- solving, and from a solution to a plan file ---------------------------------------------
def solve_rearrangement(
    rearrangement: Rearrangement,
    task_planner: str = "sdar",
    max_time: float = 60.0,
    progress: Callable[[int, int], None] | None = None,
) -> Solution:
    """Solve with SDAR-M over ``task_planner`` (``sdar`` or ``baseline``) within ``max_time``
    [s] (> 0, ``inf`` for no limit, checked as by :func:`solvers.solve.solve`);
    ``progress(done, total)`` is called before every step and at the end.

    Raises:
        ParameterError: ``max_time`` out of range or an unknown ``task_planner``.
    """
    from solvers.sdar.planners import make_task_planner
    from solvers.sdar.solver import SdarOptions, SdarSolver

    max_time = MAX_TIME.check("max_time", max_time)
    planner = make_task_planner(task_planner)
    # The baseline motion planner: one arm works while the other waits at its retract pose.
    # The quick motion stream differs from the full one only under SDAR-M's ladder.
    motion = rearrangement.motion
    options = SdarOptions(
        max_time=max_time,
        progress=progress,
        one_arm_at_a_time=motion == "sequential",
        quick_attempts=SdarOptions.quick_attempts if motion == "sdar" else 0,
    )
    return SdarSolver(rearrangement.problem, planner, options).solve()


def timeline(
    plan: Sequence[Action], trace: Sequence[Mapping[str, Any]] = ()
) -> list[MotionSegment | GripperEvent]:
    """The plan's motions and gripper events in order (both events of a ``*-both`` action).

    ``trace``: the solver's per-task records (kind, objects, number of motions), used to label
    the motions."""
    labels = [
        (str(r["kind"]), tuple(str(o) for o in r["objects"]))
        for r in trace
        for _ in range(int(r["motions"]))
    ]
    items: list[MotionSegment | GripperEvent] = []
    motions = 0
    for action in plan:
        if action.name == "move":
            result = action.args[1]
            assert isinstance(result, MotionResult) and result.trajectory is not None
            traj = result.trajectory
            kind, objects = labels[motions] if motions < len(labels) else ("", ())
            items.append(MotionSegment(traj.t, traj.q, result.level or "", objects, kind))
            motions += 1
            continue
        kind = "grasp" if action.name.startswith("pick") else "release"
        args = action.args
        parts = [args[0:5]] if action.name in ("pick", "place") else [args[1:6], args[6:11]]
        for arm, obj, _pose, grasp, _conf in parts:
            items.append(GripperEvent(arm, kind, obj, inverse(grasp.T_object_tcp)))
    return items


def step_times(solution: Solution) -> list[tuple[float, float]]:
    """``(selection, motion)`` planning time [s] of every synchronous step (motion). A task's
    selection time and the time of the motions it tried in vain are shared equally by the
    motions it executed, so the steps add up to the time of the decisions."""
    out: list[tuple[float, float]] = []
    for record in solution.trace:
        motions = list(record["motion_times"])
        wasted = float(record["motion_time"]) - sum(motions)
        for m in motions:
            out.append((record["selection_time"] / len(motions), m + wasted / len(motions)))
    return out


def plan_file_from_solution(
    rearrangement: Rearrangement,
    solution: Solution,
    metrics: Mapping[str, float | int | str] | None = None,
    gripper_time: float = GRIPPER_TIME,
) -> PlanFile:
    """The timed plan file of a solved rearrangement (planning figures in ``metrics``)."""
    if solution.plan is None:
        raise ParameterError("solution has no plan (status: " + solution.status.value + ")")
    instance = rearrangement.instance
    stats = solution.statistics
    figures: dict[str, float | int | str] = {
        "planning_time": float(stats.get("planning_time", 0.0)),
        "planning_time_selection": float(stats.get("selection_time", 0.0)),
        "planning_time_motion": float(stats.get("motion_time", 0.0)),
    }
    figures.update(metrics or {})
    return build_plan_file(
        rearrangement.ctx.scene,
        instance.name,
        {o.name: o.start.as_tuple() for o in instance.objects},
        {o.name: o.size for o in instance.objects},
        timeline(solution.plan, solution.trace),
        figures,
        gripper_time=gripper_time,
        q_start=rearrangement.home.q,
    )
