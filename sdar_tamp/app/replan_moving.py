"""Re-plan while the arms move: the first valid plan as soon as there is one, shorter ones
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
2. A fresh continuation (:func:`~sdar_tamp.app.replanning.fresh_continuation`, without
   infeasibility proofs) starts where the arms can leave the plan with empty grippers
   (:func:`~sdar_tamp.app.replan_starts.next_start`: a clear cut, not at grasps, or a
   braked stop on the way to the next grasps): the first one, from ``resume`` on, the arms
   reach once a solve of the objects left is expected to end (at least :data:`MIN_BUDGET`;
   expected: :data:`AHEAD` times the time per object of the last solve, before any the
   repair's time per object, :func:`_per_object`), from the objects where the plan leaves
   them there; its solve's time limit is the time until the arms get there, less
   :data:`RESERVE` for the checks (times on the configuration's clock, ``config.sdar.clock``:
   the wall time unless set otherwise). A solve out of time doubles the time expected per
   object. The earlier the start, the more a fresh plan may save; the time a solve needs is
   not known before it ends (a fraction of a second to tens of seconds on the paper suite,
   depending on the objects left and the machine's load), and one start gives a plan that
   may be 10-20% longer or shorter than from a state a rounding error away (motions planned
   from other ends: the solve's outcome is a draw), so the search goes on.
3. A fresh plan replaces the plan the arms execute, yielded as the next outcome
   (``replanned``, its ``alternative`` the replaced plan's execution), when it ends more than
   :data:`~sdar_tamp.app.replanning.SAVING` of that execution from ``resume`` earlier,
   replays without violation from its start, and all that is done before the arms get there.
   Either way the next solve starts from a later state of the plan kept, at most
   :data:`TRIES` solves in all, none past the re-plan's time limit: each outcome after the
   first is shorter than the one before.

When the repair is ready only once the arms stand at its cut (no way left to run: the
observation came in at or just before the cut), the comparison while moving could start only
after the repair's first steps, and a fresh plan that orders those differently would be out
of reach. Then the arms may wait there :data:`LOOK` more, when a fresh solve is expected to
end in that time (:func:`_worth_a_look`): one fresh
solve from the cut itself, given instead of the repair when it is shorter, valid and found
within that time; otherwise the repair is given at once and steps 1-3 follow (then with
braked stops too, which let a solve that ends while the arms are on their way to the
repair's first grasps still change them).

A fresh solve from a cut point after ``resume`` plans fewer objects than one from ``resume``
(the repair's first steps are done by then), so the plan kept may be longer than the
synchronous comparison's; its latency (the wall time from the observation to that plan) is
that of the old definition, the time until the final plan.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from sdar_tamp.app.cache import PlannerCache
from sdar_tamp.app.config import PlannerConfig
from sdar_tamp.app.replan_starts import next_start
from sdar_tamp.app.replanning import (
    ReplanOutcome,
    fresh_continuation,
    replan,
    shorter,
    timed_and_checked,
)
from sdar_tamp.app.splicing import check_from
from sdar_tamp.logs import get_logger
from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_rules import STILL_TOL, TIME_TOL
from sdar_tamp.plan_state import PlanState, cut_point
from sdar_tamp.world.collision import CollisionWorld
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.observed import ObservedState
from sdar_tamp.world.scene import Scene

LOG = get_logger(__name__)
MIN_BUDGET = 0.3  #: [s] of wall time a fresh solve gets at least (else a later start)
RESERVE = 0.2  #: [s] of wall time kept for the checks after a fresh solve, before the cut
TRIES = 8  #: fresh solves at most (a timed-out one is tried again from a later start)
#: A fresh solve's expected time [s] is this times the last one's (which planned as many
#: objects or more): the next start is the first the arms reach that much later.
AHEAD = 1.25
#: [m] a braked stop's moving tools are at least this much over the tallest object (lower,
#: their fingers reach down around the objects: they come down to grasps or leave
#: placements, :mod:`~sdar_tamp.app.replan_starts`): the margin of the optimiser's lifts
#: over the objects (``streams.motion.shape.ShapeOptions.lift_margin``).
ABOVE = 0.015
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
    then, when that is a repair that changed the plan, each shorter plan found while the arms
    execute the one before (:func:`improvements`). ``observed_at``: the time the observation
    came in on the configuration's clock (``config.sdar.clock``: ``time.perf_counter()``,
    the wall time, unless set otherwise; default: the call). Each outcome's ``latency`` is
    the time from then to its plan; the other arguments are :func:`replan`'s."""
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
                        tries=1, brakes=False)  # fmt: skip
        if fresh is not None:
            yield fresh
            return
    yielded = clock()
    yield first
    arrival = Arrival(max(yielded, observed_at + (first.resume - at)), first.resume)
    yield from improvements(instance, first, arrival, config=config, scene_path=scene_path,
                            cache=cache, validate=validate, observed_at=observed_at)  # fmt: skip


def _worth_a_look(repaired: ReplanOutcome, spent: float, look: float) -> bool:
    """Whether a fresh solve from ``repaired``'s cut may end within ``look`` [s]: one that
    moves ``n`` objects is expected to take ``spent`` (the repair's time, [s]) times ``n / 4``
    (the repair planned one task again and the motion rejoining the old plan, about two steps
    of a solve; a fresh solve makes about ``n / 2`` steps, two objects for two arms)."""
    assert repaired.plan is not None
    left = _left(repaired.plan, repaired.resume - 1e-6)
    return look >= MIN_BUDGET + RESERVE and _per_object(spent) * left <= look


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
    brakes: bool = True,
) -> ReplanOutcome | None:
    """The first plan :func:`improvements` gives (None when it gives none)."""
    return next(improvements(instance, repaired, arrival, config=config, scene_path=scene_path,
                             cache=cache, validate=validate, observed_at=observed_at,
                             tries=tries, brakes=brakes), None)  # fmt: skip


def improvements(
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
    brakes: bool = True,
) -> Iterator[ReplanOutcome]:
    """Fresh continuations, each shorter than the plan before it (``repaired``'s first), from
    starts of that plan (:func:`~sdar_tamp.app.replan_starts.next_start`: clear cuts, and
    braked stops unless ``brakes`` is False) found before the arms (timed by ``arrival``)
    reach them (see the module docstring), as ``replanned`` outcomes. ``tries``: the fresh
    solves at most."""
    if repaired.plan is None:
        return
    best = repaired
    clock = config.sdar.clock
    observed_at = clock() if observed_at is None else observed_at
    cache = cache or PlannerCache()
    world = cache.world(scene_path or instance.scene_path(), config.trajopt)
    scene = world.ctx.scene
    kins = dict(world.ctx.kinematics)  # the world's, built once with it
    collision = CollisionWorld(scene)
    sizes = {o.name: o.size for o in instance.objects}
    for seen in repaired.plan.observations:
        sizes.update(seen.added)
    starts = {o.name: o.start.as_tuple() for o in instance.objects}
    deadline = observed_at + config.max_time
    above = max(size[2] for size in sizes.values()) + ABOVE  # braked stops' tools at least
    t = repaired.resume
    rate = AHEAD * _per_object(repaired.latency)  # [s] a solve is expected to take per object
    k = 0  # fresh solves so far
    while k < tries:
        assert best.plan is not None
        # the earliest plan time the arms reach once a solve of the objects left could end
        need = max(MIN_BUDGET, rate * _left(best.plan, t))
        now = clock()
        earliest = max(t, arrival.resume + now + need + RESERVE - arrival.start)
        start = next_start(best.plan, earliest, starts, scene, kins, brakes=brakes, above=above)
        if start is None or not _left(best.plan, start.t):
            return  # no start left, or nothing left to plan from it
        by = min(arrival.at(start.t), deadline)
        budget = by - clock() - RESERVE  # (the search for the start took some of it)
        if by - now - RESERVE < MIN_BUDGET or budget <= 0.0:  # the time limit is near
            if now + MIN_BUDGET + RESERVE > deadline:
                return
            t = start.t + 1e-6
            continue
        k += 1
        began = clock()
        fresh = fresh_continuation(world, config.replace(max_time=budget, seed=config.seed + k - 1),
                                   instance, start.prefix, dict(start.resting), sizes,
                                   start.free, prove=False)  # fmt: skip
        spent = clock() - began
        ends = "none" if fresh.plan is None else f"{fresh.plan.duration:.3f} s"
        LOG.debug("fresh solve %d from %s %.3f s (%.3f s on): %s %s (best %.3f s) in %.3f s "
                  "of %.3f s", k - 1, "a braked stop at" if start.braked else "the clear cut",
                  start.t, start.t - repaired.resume, fresh.status, ends, best.plan.duration,
                  spent, budget)  # fmt: skip
        # the next try starts once the arms move on from there (no state tried twice)
        t = _moving_on(best.plan, cut_point(best.plan, start.t).t if start.braked else start.t)
        left = _left(best.plan, start.t)
        if fresh.plan is None:  # out of time: twice the time; else no plan from there
            rate = max(rate, 2.0 * budget / left) if fresh.status == "timeout" else rate
            continue
        rate = AHEAD * spent / left
        if not shorter(fresh.plan, best.plan, repaired.resume):
            continue
        q0 = start.prefix.q[-1]
        begin = PlanState(float(start.prefix.t[-1]), q0, {}, dict(start.resting))
        _, bad, _ = check_from(instance, fresh.plan, scene, kins, collision, begin)
        if bad is not None or clock() > by:
            continue
        out = _outcome(instance, scene, repaired, best, fresh.plan, clock() - observed_at,
                       validate)  # fmt: skip
        if out.valid is False:  # never a plan the replay rejects
            continue
        yield out
        best = out
        t = _moving_on(fresh.plan, float(start.prefix.t[-1]))  # the same on the new plan


def _per_object(repair_time: float) -> float:
    """A fresh solve's expected time [s] per object to move, from the repair's ``repair_time``
    [s]: the repair planned one task again and the motion rejoining the old plan, about two
    steps of a solve, where a fresh solve makes about one step per two objects (two arms)."""
    return repair_time / 4.0


def _moving_on(plan: PlanFile, t: float) -> float:
    """The first sample time [s] of ``plan`` at which its arms, at rest at ``t`` [s] (or,
    moving, once at rest again), have moved on (the plan's end if never)."""
    moves = np.abs(np.diff(plan.q, axis=0)).max(axis=1) > STILL_TOL  # (n - 1,) intervals
    i = int(np.searchsorted(plan.t, t - TIME_TOL))
    rest = np.flatnonzero(~moves[i:])  # at rest from there on ...
    if not len(rest):
        return float(plan.t[-1])
    after = np.flatnonzero(moves[i + rest[0] :])  # ... until the first motion after that
    return float(plan.t[i + rest[0] + after[0] + 1]) if len(after) else float(plan.t[-1])


def _left(plan: PlanFile, t: float) -> int:
    """The objects ``plan`` grasps after ``t`` [s]."""
    return len({e.object for e in plan.events if e.type == "grasp" and e.t > t})


def _outcome(
    instance: Instance, scene: Scene, repaired: ReplanOutcome, replaced: ReplanOutcome,
    plan: PlanFile, latency: float, validate: bool,
) -> ReplanOutcome:  # fmt: skip
    """The ``replanned`` outcome of ``plan``, a fresh continuation of ``repaired`` that
    replaces ``replaced`` (its execution the ``alternative``)."""
    plan, valid, violation = timed_and_checked(plan, latency, instance, scene, validate)
    assert replaced.plan is not None
    known = {o.name for o in instance.objects}
    moved = tuple(dict.fromkeys(
        e.object for e in plan.events
        if e.type == "release" and e.t > repaired.cut and e.object not in known
    ))  # fmt: skip
    return ReplanOutcome(
        "replanned", plan, repaired.cut, latency, (), (), moved, valid, violation,
        replaced.plan.duration, False, repaired.resume,
    )  # fmt: skip
