"""Re-planning from an observed state: the plan being executed, the time reached and what the
camera sees -> one new plan, the executed prefix spliced with a continuation.

:func:`replan` works in five steps:

1. The state at the time ``at`` reached follows from the plan (:func:`~sdar_tamp.plan_state.
   state_at`: each arm's configuration, what it holds, where the other objects rest); the
   observation (:mod:`sdar_tamp.world.observed`) replaces the resting arrangement, and an
   impossible one is refused at its entry of the file (objects overlapping, off the
   workspace, unknown, held, or inside an arm at the configuration reached).
2. The arms cannot jump: the plan runs on to its next cut point (:func:`~sdar_tamp.plan_state.
   cut_point`: every arm at rest with an empty gripper, the events of that instant left to
   the continuation); the stretch from ``at`` to the cut is replayed in the observed world
   (the validator's walk). Where it meets the change, the arms brake on their way instead
   (:mod:`sdar_tamp.app.braking`: no gripper acting before they stand still; an object in
   hand is then put down: where the plan would release it, where it was grasped, or below) and a
   fresh continuation starts there; when that stretch meets it too, the re-plan ends as
   ``infeasible``. When the
   cut falls on grasps about to happen and the plan's next cut is reached without violation
   through them, that later cut is taken: the arms then stop clear of the objects rather than
   with open fingers around them.
3. Repair: the rest of the old plan after the cut is kept as it is when it still validates
   from the cut in the observed world (a change that touches none of its steps), or with the
   tasks the change touches planned again (:mod:`sdar_tamp.app.repair`). A repair that changed
   the plan is compared with a fresh continuation (step 4) solved within the time left of the
   limit: the shorter execution of the two is kept (the repair unless the fresh one saves
   more than :data:`SAVING` of its execution from the cut, or when the fresh solve gives no
   plan in time or one that does not replay from the cut); both solves are
   seeded, so the same inputs give the same choice whenever the fresh solve ends in time.
4. Otherwise a fresh SDAR solve of the objects resting at the cut
   (:func:`~sdar_tamp.app.replan_world.continuation_instance`: a removed object's tasks are
   gone, an added object without a goal stays unless it blocks a goal, then it is moved
   away), the arms starting where they stand and idle arms waiting at home.
5. The new plan is the prefix, a still hold at the cut (at least one sample spacing, and
   until the dwells begun before it are over), then the continuation; it records the
   observation (``observations`` of the plan file), with which the independent validator
   replays it: at ``at`` the observed arrangement replaces the planned one.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sdar_tamp.app.braking import brake, put_down, still_until_dwells_end
from sdar_tamp.app.cache import PlannerCache, PlanningWorld
from sdar_tamp.app.config import PlannerConfig
from sdar_tamp.app.plan_export import plan_file_from_solution
from sdar_tamp.app.problem import rearrangement_problem
from sdar_tamp.app.repair import repair as repair_plan
from sdar_tamp.app.replan_world import continuation_instance, start_configuration
from sdar_tamp.app.solving import solve_rearrangement
from sdar_tamp.app.splicing import check_from, cut_at, splice, tail, walk_from
from sdar_tamp.plan_file import PlanFile, PlanObservation
from sdar_tamp.plan_rules import TIME_TOL
from sdar_tamp.plan_state import Cut, PlanState, cut_point, prefix_plan, state_at
from sdar_tamp.replay import validate_plan
from sdar_tamp.replay_walk import ReplayWalk
from sdar_tamp.world.collision import CollisionWorld, ObjectBox
from sdar_tamp.world.instance import Instance, Pose2D
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.observed import (
    ObservedState,
    Resting,
    check_clear_of_arms,
    observed_arrangement,
)
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray
from streams.stream_types import ArmConf, CellConf

Pose3 = tuple[float, float, float]
STATUSES = ("repaired", "replanned", "infeasible", "timeout")
#: Share of a repaired plan's execution from the cut that a fresh continuation must save to
#: replace it: the repair keeps the old plan's structure (its grasps, the order of its tasks),
#: which a fresh plan a few samples shorter is not worth giving up.
SAVING = 0.01


@dataclass(frozen=True)
class ReplanOutcome:
    """What :func:`replan` produced: ``status`` (``repaired``: the old plan's rest kept;
    ``replanned``: a fresh continuation; ``infeasible``, ``timeout``), the spliced ``plan``
    (None without one), the ``cut`` time [s], the re-planning ``latency`` [s], the reasons
    and the objects ``blocking`` a plan; ``valid``/``violation``: the independent replay of
    the whole new plan (when asked); ``alternative``: where a changed repair was compared with
    a fresh continuation, the execution time [s] of the plan not kept (None: no comparison, or
    the fresh solve gave no plan); ``changed``: the outcome is a repair that changed the old
    plan's rest (a fresh continuation might be shorter: :mod:`sdar_tamp.app.replan_moving`
    compares them while the arms move); ``resume``: the plan time [s] where the continuation
    begins (the end of the prefix's hold)."""

    status: str
    plan: PlanFile | None
    cut: float
    latency: float
    reasons: tuple[str, ...] = ()
    blocking: tuple[str, ...] = ()
    moved_away: tuple[str, ...] = ()
    valid: bool | None = None
    violation: str = ""
    alternative: float | None = None
    changed: bool = False
    resume: float = 0.0

    @property
    def success(self) -> bool:
        return self.plan is not None and self.valid is not False


def replan(
    instance: Instance,
    plan: PlanFile,
    at: float,
    observed: ObservedState,
    *,
    config: PlannerConfig | None = None,
    scene_path: Path | None = None,
    cache: PlannerCache | None = None,
    validate: bool = True,
    repair: bool = True,
    retry: bool = True,
    compare: bool = True,
) -> ReplanOutcome:
    """Re-plan ``plan`` of ``instance`` at time ``at`` [s] from the ``observed`` state (see
    the module docstring). ``config``: the planner configuration of a fresh continuation
    (its ``seed``, budgets and time limit); ``scene_path``: the cell (default: the
    instance's); ``cache``: keeps the world and motion planner between calls; ``validate``:
    replay the whole new plan independently; ``repair``: try keeping the old plan's rest
    first (False: always a fresh continuation); ``retry``: when a fresh continuation fails the
    replay (``validate``), solve once more with the next seed and keep that one if valid;
    ``compare``: compare a repair that changed the plan with a fresh continuation and keep the
    shorter execution (False: keep the repair).

    Raises:
        ObservedStateError: the observed state cannot be (located at its file entry).
        ParameterError: ``at`` outside the plan.
    """
    config = config or PlannerConfig()
    cache = cache or PlannerCache()
    world = cache.world(scene_path or instance.scene_path(), config.trajopt)
    clock = config.sdar.clock  # wall time unless the configuration says otherwise
    started = clock()
    scene = world.ctx.scene
    kins = dict(world.ctx.kinematics)  # the world's, built once with it
    sizes = {o.name: o.size for o in instance.objects}
    for seen in plan.observations:
        sizes.update(seen.added)
    starts = {o.name: o.start.as_tuple() for o in instance.objects}
    past = dataclasses.replace(plan, observations=tuple(o for o in plan.observations if o.t < at))
    state = state_at(past, starts, scene, at, kins)
    resting = {n: Resting(sizes[n], _pose(p)) for n, p in state.resting.items()}
    known = tuple(sorted(set(sizes)))
    arrangement = observed_arrangement(observed, resting, state.holder, known, instance.workspace)
    collision = CollisionWorld(scene)
    grips = {e.arm: e.T_tcp_object for e in past.events if e.t < at and e.type == "grasp"}
    held = {
        arm: (obj, ObjectBox(kins[arm].fk_tcp(scene.layout.part(state.q, arm)) @ grips[arm],
                             sizes[obj]))
        for arm, obj in state.held.items()
    }  # fmt: skip
    check_clear_of_arms(arrangement, scene, state.q, at, observed, collision, held)
    for obj in observed.added:
        sizes[obj.name] = obj.size
    seen = PlanObservation(
        at,
        {n: r.pose.as_tuple() for n, r in sorted(arrangement.items())},
        {o.name: o.size for o in observed.added},
    )
    old = dataclasses.replace(past, observations=(*past.observations, seen))
    cut = cut_point(old, at)
    prefix = prefix_plan(old, cut)
    walk = walk_from(instance, prefix, scene, kins, collision, state)
    found = walk.walk(float(prefix.t[-1]), at)
    braked = False
    if found is not None:  # the arms meet the change on their way: stop them short of it
        short = _stop_short(world, config, instance, old, at, kins, collision, state, grips,
                            sizes)  # fmt: skip
        if short is None:
            return ReplanOutcome(
                "infeasible", None, cut.t, clock() - started,
                (f"the running plan meets the observed world at t = {found.t:.3f} s before the "
                 f"arms can stop at t = {cut.t:.3f} s (nor braking on their way): "
                 f"{found.kind}: {found.message}",),
                _objects_in(found.message, sizes),
            )  # fmt: skip
        cut, prefix, walk = short
        braked = True
    elif any(abs(e.t - cut.t) <= 1e-9 for e in old.events):
        # the arms stop at grasps about to happen: when those still hold in the observed
        # world, the plan runs on through them to its next cut (its grippers clear again)
        later = cut_point(old, cut.t + 1e-6)
        longer = prefix_plan(old, later)
        ahead = walk_from(instance, longer, scene, kins, collision, state)
        if later.t > cut.t and ahead.walk(float(longer.t[-1]), at) is None:
            cut, prefix, walk = later, longer, ahead
    at_cut = dict(walk.rest)
    t_hold = float(prefix.t[-1])
    if repair and not braked:  # braked off the plan's timeline, its rest cannot resume
        rest = splice(prefix, tail(old, _resume(old, cut, float(prefix.t[-1]))))
        empty = PlanState(t_hold, prefix.q[-1], {}, at_cut)
        fixed = repair_plan(world, config, instance, rest, empty, kins, collision, sizes)
        if fixed is not None:
            kept, moved, changed = fixed
            left = config.max_time - (clock() - started)
            if not (compare and changed and left > 0.0):
                return _finish("repaired", kept, instance, scene, cut, clock() - started,
                               validate, moved, changed=changed, resume=t_hold)  # fmt: skip
            # the repair changed the plan: a fresh continuation within the time left, and
            # the shorter execution of the two (the repair on a tie or a failed fresh one)
            other = fresh_continuation(world, config.replace(max_time=left), instance, prefix,
                                       at_cut, sizes, prove=False)  # fmt: skip
            alternative = None if other.plan is None else other.plan.duration
            if other.plan is not None and shorter(other.plan, kept, t_hold):
                _, bad, _ = check_from(instance, other.plan, scene, kins, collision, empty)
                if bad is None:
                    return _finish("replanned", other.plan, instance, scene, cut,
                                   clock() - started, validate, other.moved, kept.duration,
                                   resume=t_hold)  # fmt: skip
                alternative = None  # the replay rejects it: no alternative
            return _finish("repaired", kept, instance, scene, cut, clock() - started, validate,
                           moved, alternative, resume=t_hold)  # fmt: skip
    slices = {a: scene.layout.slice(a) for a in scene.arm_names}
    moving = prefix.q[prefix.t >= at - 1e-9]  # braked arms leave directly, not by a lift
    free = frozenset(  # an arm that put an object down leaves by a lift
        a for a, sl in slices.items()
        if braked and a not in state.held and np.ptp(moving[:, sl], 0).max() > 0
    )  # fmt: skip
    fresh = fresh_continuation(world, config, instance, prefix, at_cut, sizes, free)
    if fresh.plan is None:
        reasons = fresh.reasons
        status = "timeout" if fresh.status == "timeout" else "infeasible"
        blocking = _objects_in(" ".join(reasons), sizes)
        return ReplanOutcome(status, None, cut.t, clock() - started, reasons,
                             blocking, fresh.moved)  # fmt: skip
    out = _finish("replanned", fresh.plan, instance, scene, cut, clock() - started, validate,
                  fresh.moved, resume=t_hold)  # fmt: skip
    if out.valid is False and retry:  # rare: one more solve with the next seed
        again = replan(instance, plan, at, observed, config=config.replace(seed=config.seed + 1),
                       scene_path=scene_path, cache=cache, validate=True, repair=False,
                       retry=False)  # fmt: skip
        if again.valid:
            return dataclasses.replace(again, latency=clock() - started)
    return out


@dataclass(frozen=True)
class Fresh:
    """A fresh continuation: the spliced ``plan`` (None without one), the added objects it
    moves away, and the solve's ``status`` and ``reasons`` without a plan."""

    plan: PlanFile | None
    moved: tuple[str, ...]
    status: str = ""
    reasons: tuple[str, ...] = ()


def fresh_continuation(
    world: PlanningWorld, config: PlannerConfig, instance: Instance, prefix: PlanFile,
    at_cut: dict[str, Pose3], sizes: dict[str, tuple[float, float, float]],
    free: frozenset[str] = frozenset(), *, prove: bool = True,
) -> Fresh:  # fmt: skip
    """A fresh SDAR solve of the objects resting at the cut (``at_cut``), spliced after
    ``prefix``: the arms start where ``prefix`` ends, idle arms at home; those in ``free``
    (stopped in the middle of their motions) leave directly; ``prove``: the solve's
    infeasibility proofs first (their diagnosis names the blocking objects)."""
    scene = world.ctx.scene
    cont_instance, moved = continuation_instance(instance, at_cut, sizes, config.seed)
    slices = {a: scene.layout.slice(a) for a in scene.arm_names}
    start = start_configuration(_home(world), prefix.q[-1], slices, free)
    r = rearrangement_problem(cont_instance, world.ctx, config=config, planner=world.planner,
                              start=start)  # fmt: skip
    solution = solve_rearrangement(r, prove=prove)
    if solution.plan is None:
        reasons = tuple(solution.diagnosis) or (f"no plan ({solution.status.value})",)
        return Fresh(None, moved, solution.status.value, reasons)
    return Fresh(splice(prefix, plan_file_from_solution(r, solution)), moved)


def shorter(fresh: PlanFile, repaired: PlanFile, t_from: float) -> bool:
    """Whether ``fresh`` ends more than :data:`SAVING` of ``repaired``'s execution after
    ``t_from`` [s] before it."""
    return fresh.duration - t_from < (1.0 - SAVING) * (repaired.duration - t_from) - TIME_TOL


def _stop_short(
    world: PlanningWorld, config: PlannerConfig, instance: Instance, plan: PlanFile, at: float,
    kins: dict[str, ArmKinematics], collision: CollisionWorld, state: PlanState,
    grips: dict[str, FloatArray], sizes: dict[str, tuple[float, float, float]],
) -> tuple[Cut, PlanFile, ReplayWalk] | None:  # fmt: skip
    """The arms braked on their way from ``at`` (:func:`~sdar_tamp.app.braking.brake`), and
    what they hold (``state.held``, at ``grips``) put down
    (:func:`~sdar_tamp.app.braking.put_down`): the cut where they stand still with empty
    grippers, the prefix with its hold and its walk from ``state``, when that stretch meets
    nothing in the observed world; else None."""
    scene = world.ctx.scene
    v_max, a_max = scene.joint_array("velocity_limit"), scene.joint_array("acceleration_limit")
    stop = brake(plan, at, v_max, a_max)
    if stop is None:
        return None
    if not state.held:
        pieces: Iterator[PlanFile] = iter([stop.plan])
    else:  # the braked stretch replayed first: where the objects rest when the arms stop
        base = still_until_dwells_end(stop.plan)  # a grasp's dwell may not be over
        walk = walk_from(instance, base, scene, kins, collision, state)
        if walk.walk(float(base.t[-1]), at) is not None:
            return None
        downs = put_down(world.planner, plan, at, base.q[-1], state.held, grips,
                         dict(walk.rest), sizes, config.gripper_time)  # fmt: skip
        pieces = (splice(base, down) for down in downs)
    for piece in pieces:
        end = Cut(len(piece.t) - 1, float(piece.t[-1]), len(piece.events))
        prefix = prefix_plan(piece, end)
        walk = walk_from(instance, prefix, scene, kins, collision, state)
        if walk.walk(float(prefix.t[-1]), at) is None:
            return end, prefix, walk
    return None


def _resume(plan: PlanFile, cut: Cut, t_hold: float) -> Cut:
    """Where ``plan`` goes on after a prefix held still until ``t_hold`` [s]: there, when the
    plan itself stands still from ``cut`` to then with no event between (a gripper's dwell:
    not waited twice); else at ``cut``."""
    resume = cut_at(plan, t_hold)
    q = plan.q[cut.index : resume.index + 1]
    if resume.events == cut.events and np.abs(q - plan.q[cut.index]).max() <= 1e-9:
        return resume
    return cut


def _pose(p: tuple[float, ...]) -> Pose2D:
    return Pose2D(float(p[0]), float(p[1]), float(p[2]))


def _home(world: PlanningWorld) -> CellConf:
    ctx = world.ctx
    return CellConf(*(ArmConf(a, tuple(float(x) for x in ctx.home(a))) for a in ctx.arm_names))


def _objects_in(text: str, sizes: dict[str, tuple[float, float, float]]) -> tuple[str, ...]:
    """The object names ``text`` mentions (as words), in order of first mention."""
    words = re.findall(r"[A-Za-z0-9_.\-]+", text)
    return tuple(dict.fromkeys(w for w in words if w in sizes))


def _finish(
    status: str, plan: PlanFile, instance: Instance, scene: Scene, cut: Cut, latency: float,
    validate: bool, moved: tuple[str, ...] = (), alternative: float | None = None, *,
    changed: bool = False, resume: float = 0.0,
) -> ReplanOutcome:  # fmt: skip
    plan, valid, violation = timed_and_checked(plan, latency, instance, scene, validate)
    return ReplanOutcome(status, plan, cut.t, latency, (), (), moved, valid, violation, alternative,
                         changed, resume)  # fmt: skip


def timed_and_checked(
    plan: PlanFile, latency: float, instance: Instance, scene: Scene, validate: bool
) -> tuple[PlanFile, bool | None, str]:
    """``plan`` with ``latency`` [s] as its planning time, whether the independent replay
    accepts it (``None`` without ``validate``) and its first violation as text ("" if none)."""
    plan = dataclasses.replace(plan, metrics=plan.metrics.updated({"planning_time": latency}))
    if not validate:
        return plan, None, ""
    report = validate_plan(instance, plan, scene)
    v = report.violation
    return plan, report.ok, "" if v is None else f"t={v.t:.3f} s: {v.kind}: {v.message}"
