"""Re-plan while the arms move: the first valid plan as soon as there is one, a shorter one
while the arms execute it (:func:`replan_while_moving`).

:func:`~sdar_tamp.app.replanning.replan` with its comparison compares a repair that changed
the plan with a fresh continuation before it returns: a second SDAR solve between the
observation and the arms' next motion. Here the repair is given to the arms as soon as it
replays valid (``replan(..., compare=False)``, the first outcome yielded), and the
comparison runs while they execute it:

1. The arms reach plan time ``t`` (at or after the continuation's start ``resume``) at wall
   time ``max(first, observed + (resume - at)) + (t - resume)``: the running plan goes on to
   its cut while the repair is planned (``observed``: the wall time the observation came in,
   at plan time ``at``), and the continuation starts when both the arms are there and the
   plan is (``first``: the wall time it was yielded).
2. The fresh continuation (:func:`~sdar_tamp.app.replanning.fresh_continuation`, without
   infeasibility proofs) starts at a cut point of the repaired plan (every arm still with an
   empty gripper, not at grasps: :func:`at_grasps`): the first, from ``resume`` on, that
   leaves the solve at least :data:`MIN_BUDGET` before the arms get there, from the objects
   where the repaired plan leaves them there; its solve's time limit is the time until the
   arms reach it, less :data:`RESERVE` for the checks (times on the configuration's clock,
   ``config.sdar.clock``: the wall time unless set otherwise). A solve that runs out of
   that time is tried again from the first cut point that leaves twice that time (at most
   :data:`TRIES` solves, none past the re-plan's time limit): the earlier the cut point, the
   more a fresh plan may save, and the time a solve needs is not known before it ends (a
   fraction of a second to tens of seconds on the paper suite, depending on the objects left
   and the machine's load).
3. It replaces the repair, yielded as a second outcome (``replanned``, its ``alternative``
   the repair's execution), when it ends more than :data:`~sdar_tamp.app.replanning.SAVING`
   of the repair's execution from ``resume`` earlier, replays without violation from its cut,
   and all that is done before the arms reach the cut; otherwise nothing more is yielded: the
   arms go on with the repair.

When the repair is ready only once the arms stand at its cut (no way left to run: the
observation came in at or just before the cut), the comparison while moving could start only
after the repair's first steps, and a fresh plan that orders those differently would be out
of reach. Then the arms may wait there :data:`LOOK` more, when a fresh solve is expected to
end in that time (:func:`_worth_a_look`): one fresh
solve from the cut itself, given instead of the repair when it is shorter, valid and found
within that time; otherwise the repair is given at once and steps 1-3 follow.

A fresh solve from a cut point after ``resume`` plans fewer objects than one from ``resume``
(the repair's first steps are done by then), so the plan kept may be longer than the
synchronous comparison's; its latency (the wall time from the observation to that plan) is
that of the old definition, the time until the final plan.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Iterator
from pathlib import Path

from sdar_tamp.app.cache import PlannerCache
from sdar_tamp.app.config import PlannerConfig
from sdar_tamp.app.replanning import (
    ReplanOutcome,
    fresh_continuation,
    replan,
    shorter,
    timed_and_checked,
)
from sdar_tamp.app.splicing import check_from, head_at
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_rules import TIME_TOL
from sdar_tamp.plan_state import Cut, PlanState, cut_point, state_at
from sdar_tamp.world.collision import CollisionWorld
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.observed import ObservedState
from sdar_tamp.world.scene import Scene
from solvers.sdar.budget import Clock

MIN_BUDGET = 0.3  #: [s] of wall time a fresh solve gets at least (else a later cut point)
RESERVE = 0.2  #: [s] of wall time kept for the checks after a fresh solve, before the cut
TRIES = 4  #: fresh solves at most (a timed-out one is tried again from a later cut point)
#: [s] the arms, when they already stand at the cut once the repair is ready, may wait there
#: more for a fresh continuation from the cut itself, given instead of the repair if shorter
#: (tried when expected to end in that time: :func:`_worth_a_look`). With no way left to
#: run, the comparison while moving can only start after the repair's first steps, and a
#: fresh plan that changes those (which objects go first, and with which) is then out of
#: reach (R5 of the paper suite, o4 nudged at its cut: the repair 12% longer).
LOOK = 1.0


@dataclasses.dataclass(frozen=True)
class Arrival:
    """When the arms reach a plan time: at time ``start`` [s] (the configuration's clock, the
    wall time by default) they are at plan time ``resume`` [s] and follow the plan in real
    time from there."""

    start: float
    resume: float

    def at(self, t: float) -> float:
        """The time [s] the arms reach plan time ``t`` [s] (at or after ``resume``)."""
        return self.start + (t - self.resume)


def replan_while_moving(
    instance: Instance,
    plan: PlanFile,
    at: float,
    observed: ObservedState,
    *,
    config: PlannerConfig | None = None,
    scene_path: Path | None = None,
    cache: PlannerCache | None = None,
    validate: bool = True,
    observed_at: float | None = None,
    look: float = LOOK,
) -> Iterator[ReplanOutcome]:
    """The outcomes of re-planning ``plan`` at ``at`` [s] from ``observed`` (see the module
    docstring): first :func:`~sdar_tamp.app.replanning.replan` without the comparison (or,
    found within ``look`` [s] more, a shorter fresh continuation: see :data:`LOOK`),
    then, when that is a repair that changed the plan, a shorter plan found while the arms
    execute it (at most one more). ``observed_at``: the time the observation came in on the
    configuration's clock (``config.sdar.clock``: ``time.perf_counter()``, the wall time,
    unless set otherwise; default: the call). Each outcome's ``latency`` is the time from
    then to its plan; the other arguments are :func:`replan`'s."""
    config = config or PlannerConfig()
    cache = cache or PlannerCache()
    clock = config.sdar.clock
    observed_at = clock() if observed_at is None else observed_at
    first = replan(instance, plan, at, observed, config=config, scene_path=scene_path,
                   cache=cache, validate=validate, compare=False)  # fmt: skip
    if first.plan is None or first.status != "repaired" or not first.changed:
        yield first
        return
    now = clock()
    if now >= observed_at + (first.resume - at) and _worth_a_look(first, now - observed_at, look):
        # the arms stand at the cut already: they may wait there up to ``look`` more for a
        # shorter fresh continuation (one solve); else they go on with the repair at once
        waiting = Arrival(now + look, first.resume)
        fresh = improve(instance, first, waiting, config=config, scene_path=scene_path,
                        cache=cache, validate=validate, observed_at=observed_at,
                        tries=1)  # fmt: skip
        if fresh is not None:
            yield fresh
            return
    yielded = clock()
    yield first
    arrival = Arrival(max(yielded, observed_at + (first.resume - at)), first.resume)
    better = improve(instance, first, arrival, config=config, scene_path=scene_path,
                     cache=cache, validate=validate, observed_at=observed_at)  # fmt: skip
    if better is not None:
        yield better


def _worth_a_look(repaired: ReplanOutcome, spent: float, look: float) -> bool:
    """Whether a fresh solve from ``repaired``'s cut may end within ``look`` [s]: one that
    moves ``n`` objects is expected to take ``spent`` (the repair's time, [s]) times ``n / 4``
    (the repair planned one task again and the motion rejoining the old plan, about two steps
    of a solve; a fresh solve makes about ``n / 2`` steps, two objects for two arms)."""
    assert repaired.plan is not None
    left = {e.object for e in repaired.plan.events if e.t >= repaired.resume}
    return look >= MIN_BUDGET + RESERVE and spent * len(left) / 4.0 <= look


def improve(
    instance: Instance,
    repaired: ReplanOutcome,
    arrival: Arrival,
    *,
    config: PlannerConfig,
    scene_path: Path | None = None,
    cache: PlannerCache | None = None,
    validate: bool = True,
    observed_at: float | None = None,
    tries: int = TRIES,
) -> ReplanOutcome | None:
    """A fresh continuation shorter than ``repaired``'s plan from one of its cut points,
    found before the arms (timed by ``arrival``) reach that cut point (see the module
    docstring), as a ``replanned`` outcome; None when there is none in time. ``tries``: the
    fresh solves at most."""
    plan = repaired.plan
    if plan is None:
        return None
    clock = config.sdar.clock
    observed_at = clock() if observed_at is None else observed_at
    cache = cache or PlannerCache()
    world = cache.world(scene_path or instance.scene_path(), config.trajopt)
    scene = world.ctx.scene
    kins = dict(world.ctx.kinematics)  # the world's, built once with it
    collision = CollisionWorld(scene)
    sizes = {o.name: o.size for o in instance.objects}
    for seen in plan.observations:
        sizes.update(seen.added)
    starts = {o.name: o.start.as_tuple() for o in instance.objects}
    deadline = observed_at + config.max_time
    t = repaired.resume
    need = MIN_BUDGET
    for _ in range(tries):
        cut = _next_cut(plan, t, arrival, need, clock)
        if cut is None:
            return None
        by = min(arrival.at(cut.t), deadline)
        budget = by - clock() - RESERVE
        if budget < MIN_BUDGET:
            return None
        prefix = head_at(plan, cut)
        resting = dict(state_at(plan, starts, scene, cut.t, kins).resting)
        fresh = fresh_continuation(world, config.replace(max_time=budget), instance, prefix,
                                   resting, sizes, prove=False)  # fmt: skip
        if fresh.plan is None:
            if fresh.status != "timeout":
                return None
            # out of time: a cut point after this one's hold (those within a gripper's dwell
            # start where it ends), with twice the time
            t, need = float(prefix.t[-1]) + 1e-6, 2.0 * budget
            continue
        if not shorter(fresh.plan, plan, repaired.resume):
            return None
        start = PlanState(float(prefix.t[-1]), prefix.q[-1], {}, resting)
        _, bad, _ = check_from(instance, fresh.plan, scene, kins, collision, start)
        if bad is not None or clock() > by:
            return None
        out = _outcome(instance, scene, repaired, fresh.plan, clock() - observed_at, validate)
        return None if out.valid is False else out  # never a plan the replay rejects
    return None


def _next_cut(
    plan: PlanFile, t: float, arrival: Arrival, need: float, clock: Clock = time.perf_counter
) -> Cut | None:
    """The first cut point of ``plan`` at or after ``t`` [s], not at grasps (see
    :func:`at_grasps`), that the arms reach at least ``need`` [s] plus :data:`RESERVE` after
    now (``clock``), before the plan's end (None if none)."""
    end = float(plan.t[-1])
    while t < end:
        cut = cut_point(plan, t)
        if cut.t >= end - 1e-9:
            return None
        if not at_grasps(plan, cut) and arrival.at(cut.t) - clock() >= need + RESERVE:
            return cut
        t = cut.t + 1e-6
    return None


def at_grasps(plan: PlanFile, cut: Cut) -> bool:
    """Whether ``plan`` grasps at ``cut``'s instant: its arms stand there at their grasps,
    fingers open. A fresh solve from there does not know them: it lifts the arms and plans
    their way back to grasps of its own (seconds more than the grasps already reached), so
    a fresh continuation from such a cut is longer than the plan it should shorten."""
    return any(e.type == "grasp" and abs(e.t - cut.t) <= TIME_TOL for e in plan.events)


def _outcome(
    instance: Instance, scene: Scene, repaired: ReplanOutcome, plan: PlanFile, latency: float,
    validate: bool,
) -> ReplanOutcome:  # fmt: skip
    plan, valid, violation = timed_and_checked(plan, latency, instance, scene, validate)
    assert repaired.plan is not None
    known = {o.name for o in instance.objects}
    moved = tuple(dict.fromkeys(
        e.object for e in plan.events
        if e.type == "release" and e.t > repaired.cut and e.object not in known
    ))  # fmt: skip
    return ReplanOutcome(
        "replanned", plan, repaired.cut, latency, (), (), moved, valid, violation,
        repaired.plan.duration, False, repaired.resume,
    )  # fmt: skip
