"""Asynchronous execution by prioritised planning in time: one timeline per arm.

:mod:`.scheduler` re-times a synchronous plan group by group: every block of a step must end
no later than it did there, so an arm done early still waits for the step's slowest arm.
:func:`schedule_timelines` drops the steps. Each arm has its own queue of blocks
(:mod:`.pieces`: its rest-to-rest motions, re-timed for the arm alone, each optionally ending
in a gripper event and the arm's dwell), and the blocks are committed one at a time,
prioritised in time: always the next block of the arm whose timeline ends first (ties: the
block done first in the synchronous plan) among the arms whose next block is ready, so an arm
that has finished its task starts its next one at once.

A block is committed at the earliest tick after its arm's timeline that

* keeps the task order's dependencies: the events on one object in their order, a dwell apart,
  and an object released only after every object resting under its footprint at that time
  has been grasped (:func:`dependencies`, read off the synchronous plan's replay);
* passes the replay (:mod:`.sweep`) against every arm's committed, time-parameterised
  trajectory (an arm stands where its timeline ends until its next block is committed), the
  table and the objects where they rest at that time: waits are inserted before the block
  until the sweep is clear.

Before a motion is committed it is shortened (:meth:`Timelines.shortcut`): its path, cut into
waypoints, has sub-paths replaced by straight joint-space segments (the first try spans the
whole transfer, between ``lift`` [m] of tool travel at either end; then pairs drawn by a
seeded generator), each kept when the time-optimal timing of the new path is shorter and it
sweeps clear against the world of that moment with the other arms standing where they are.
The synchronous paths are shaped for the arms moving together (one arm around the other);
alone, an arm often goes straighter. When the short path cannot be committed, the block's own
path is tried.

When no ready arm's block can be committed (each waits for an arm that stands in its way for
good), :class:`~sdar_tamp.schedule.scheduler.NoPlacement` is raised and the caller keeps
another schedule (:func:`sdar_tamp.schedule.schedule_async`'s, or the synchronous plan).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import PlanEvent, PlanFile
from sdar_tamp.plan_rules import check_timeline
from sdar_tamp.schedule.pieces import Block, arm_blocks
from sdar_tamp.schedule.retiming import ArmRetimer, thin
from sdar_tamp.schedule.scheduler import (
    Entry,
    NoPlacement,
    Placement,
    Schedule,
    ScheduleOptions,
    groups,
    retimer,
)
from sdar_tamp.schedule.sweep import TimedEvent, WorldSweep
from sdar_tamp.world.footprint import corners, overlap_matrix
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray


@dataclass(frozen=True)
class TimelineOptions:
    """``tries``: straight segments tried per motion (0: none); ``lift`` [m]: the tool travel
    kept at either end of a motion next to a gripper event (the straight lift and descent);
    ``seed``: of the pairs drawn; ``max_checks``: the collision queries the placement and the
    shortcuts may make together (past them no schedule is returned)."""

    tries: int = 30
    lift: float = 0.03
    seed: int = 0
    max_checks: int = 200_000

    def __post_init__(self) -> None:
        if isinstance(self.tries, bool) or not isinstance(self.tries, int) or self.tries < 0:
            raise ParameterError(f"tries: expected an integer >= 0, got {self.tries!r}")
        if isinstance(self.max_checks, bool) or not (
            isinstance(self.max_checks, int) and self.max_checks > 0
        ):
            raise ParameterError(f"max_checks: expected an integer > 0, got {self.max_checks!r}")
        if not (math.isfinite(self.lift) and self.lift >= 0.0):
            raise ParameterError(f"lift: expected a finite number >= 0, got {self.lift!r}")


def dependencies(plan: PlanFile, instance: Instance, sweep: WorldSweep) -> dict[int, list[int]]:
    """For each release of the synchronous ``plan`` (by its index in ``plan.events``): the
    earlier grasps (indices) of objects resting where the released object lands, replayed by
    ``sweep`` (the plan is assumed valid)."""
    sweep.reset([])
    sizes = {o.name: np.array(o.size[:2]) for o in instance.objects}
    out: dict[int, list[int]] = {}
    grasped: list[tuple[int, str, tuple[float, float, float]]] = []
    for i, e in enumerate(plan.events):
        row = int(np.argmin(np.abs(plan.t - e.t)))
        q_arm = plan.q[row, plan.layout.slice(plan.arm_names.index(e.arm))]
        if e.type == "grasp":
            pose = sweep.rest.get(e.object)
            if pose is not None:
                grasped.append((i, e.object, pose))
        sweep.apply(TimedEvent(row, e, q_arm), check=False)
        if e.type == "release" and e.object in sweep.rest:
            here = corners(np.array([sweep.rest[e.object]]), sizes[e.object])
            out[i] = [
                j
                for j, name, pose in grasped
                if name != e.object
                and overlap_matrix(here, corners(np.array([pose]), sizes[name]))[0, 0]
            ]
    sweep.reset([])
    return out


_Mark = tuple[list[int], list[TimedEvent], dict[int, int], int]


class Timelines(Placement):
    """The prioritised placement of every arm's blocks (see the module docstring)."""

    def __init__(
        self,
        plan: PlanFile,
        blocks: list[list[Block]],
        sweep: WorldSweep,
        options: ScheduleOptions,
        after: dict[int, list[int]],
        retimers: list[ArmRetimer],
        shortcuts: TimelineOptions,
    ) -> None:
        super().__init__(plan, blocks, sweep, options, "objects")
        self.after = {
            id(plan.events[i]): {id(plan.events[j]) for j in js} for i, js in after.items()
        }
        self.retimers, self.shortcuts = retimers, shortcuts
        self.rng = np.random.default_rng(shortcuts.seed)
        self.shortened = 0  #: motions committed along a shortened path
        self.together_count = 0  #: groups committed together at their synchronous pace
        #: every commitment: what undoes it, the queues' lengths before it, its (first) block,
        #: and whether it was a group committed together
        self.history: list[tuple[_Mark, list[int], Block, bool, int]] = []
        #: per commitment: the ticks its arm waited for the task order's dependencies and
        #: for the other arms (the sweep), and the ticks its shortened path saved
        self.waits: list[tuple[int, int, int]] = []

    def must_follow(self, e: PlanEvent, other: PlanEvent) -> bool:
        return super().must_follow(e, other) or id(other) in self.after.get(id(e), ())

    def run(self) -> PlanFile:
        queues = [list(arm) for arm in self.blocks]
        while any(queues):
            ready = [a for a in self.arms if queues[a] and self.ready(queues[a][0])]
            ready.sort(key=lambda a: (self.horizon(a), queues[a][0].sync_key, a))
            for a in ready:
                if self.sweep.checks >= self.max_checks:
                    raise NoPlacement(queues[a][0], None, "out of collision checks")
                entry = (
                    self.mark(),
                    [len(q) for q in queues],
                    queues[a][0],
                    False,
                    len(self.waits),
                )
                if self.commit_next(queues[a][0], self.slow_start(a, queues)):
                    self.history.append(entry)
                    queues[a].pop(0)
                    break
            else:
                queues = self.together(queues)
        return self.assemble()

    def together(self, queues: list[list[Block]]) -> list[list[Block]]:
        """Commit the blocks that moved together with the first waiting block in the
        synchronous plan (its group, :func:`~sdar_tamp.schedule.scheduler.groups`) at once, at
        their synchronous pace and offsets (motions shaped for moving together, such as the
        two halves of a swap), after taking back every commitment since the first of them
        committed alone; the queues left. Raises :class:`NoPlacement` when that does not go
        either."""
        heads = [q[0] for q in queues if q]
        first = min(heads, key=lambda b: (b.sync_start, b.arm))
        group = next(g for g in groups(self.blocks) if any(b is first for b in g))
        ids = {id(b) for b in group}
        back = next((i for i, h in enumerate(self.history) if id(h[2]) in ids), None)
        if back is not None and any(h[3] for h in self.history[back:]):
            back = None  # a group committed together is not taken back
        if back is not None:
            mark, lengths, _, _, waits = self.history[back]
            self.undo(mark)
            del self.waits[waits:]
            del self.history[back:]
            queues = [arm[len(arm) - n :] for arm, n in zip(self.blocks, lengths, strict=True)]
        members = [b for b in group if any(b is q[0] for q in queues if q)]
        taken = {b.arm for b in members}
        members = [b for b in group if b.arm in taken]
        fits = all(
            [b for b in members if b.arm == arm]
            == queues[arm][: sum(b.arm == arm for b in members)]
            for arm in taken
        )
        if len(taken) < 2 or not fits:
            raise NoPlacement(first, None, "no ready arm's next block can be committed")
        entry = (self.mark(), [len(q) for q in queues], first, True, len(self.waits))
        start = min(b.sync_index for b in members)
        self.place([Entry(b.arm, b, b.q_sync, b.sync_index - start) for b in members])
        self.history.append(entry)
        self.together_count += 1
        for arm in taken:
            del queues[arm][: sum(b.arm == arm for b in members)]
        return queues

    def commit(
        self, entry: Entry, s: int, rows: FloatArray, k0: int, timed: TimedEvent | None
    ) -> None:
        horizon = self.horizon(entry.arm)
        ready = max(horizon, self.earliest(entry) + entry.offset)
        saved = len(entry.block.q) - len(entry.q) if entry.q is not entry.block.q_sync else 0
        self.waits.append((ready - horizon, s - ready, saved))
        super().commit(entry, s, rows, k0, timed)

    def figures(self) -> tuple[tuple[str, float], ...]:
        """What the placement measured: waits for dependencies and for other arms [s] (summed
        over the arms), motions shortened and the time they saved [s], groups committed
        together, motions committed."""
        dep, sweep, saved = (sum(w[i] for w in self.waits) * self.tick for i in range(3))
        return (
            ("wait_dependencies", dep),
            ("wait_other_arms", sweep),
            ("shortened", float(self.shortened)),
            ("shortcut_saved", saved),
            ("together", float(self.together_count)),
            ("motions", float(len(self.waits))),
        )

    def slow_start(self, arm: int, queues: list[list[Block]]) -> bool:
        """Whether the arm's next block leaves a gripper event (its previous block had one)."""
        done = len(self.blocks[arm]) - len(queues[arm])
        return done > 0 and self.blocks[arm][done - 1].event is not None

    def commit_next(self, block: Block, slow_start: bool) -> bool:
        """Commit ``block`` along a shortened path, else its own; False when neither goes."""
        paths = [block.q]
        short = self.shortcut(block, slow_start)
        if short is not None:
            paths.insert(0, short)
        for q in paths:
            try:
                self.place([Entry(block.arm, block, q, 0)])
            except NoPlacement:
                continue
            self.shortened += q is not block.q
            return True
        return False

    def shortcut(self, block: Block, slow_start: bool) -> FloatArray | None:
        """A faster path for ``block`` (samples one tick apart), or None (see the module
        docstring)."""
        arm, timer = block.arm, self.retimers[block.arm]
        path_timer = timer.timer
        if path_timer is None or self.shortcuts.tries == 0 or len(block.q) < 4:
            return None
        slow_end = block.event is not None
        path = thin(block.q, timer.spacing)
        if len(path) < 3:
            return None
        tool = (timer.kinematics.fk_batch(path) @ timer.kinematics.T_tool0_tcp)[:, :3, 3]
        travel = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(tool, axis=0), axis=1))])
        lo = int(np.searchsorted(travel, self.shortcuts.lift)) if slow_start else 0
        hi = len(path) - 1
        if slow_end:
            hi = int(np.searchsorted(travel, travel[-1] - self.shortcuts.lift, side="right")) - 1
        if hi - lo < 2:
            return None
        best = block.q
        pairs = [(lo, hi)]
        for _ in range(self.shortcuts.tries - 1):
            i, j = sorted(int(x) for x in self.rng.integers(lo, hi + 1, size=2))
            pairs.append((i, j))
        for i, j in pairs:
            if j - i < 2:
                continue
            current = thin(best, timer.spacing) if best is not block.q else path
            # map the pair onto the current path by the nearest waypoints of the original
            a = int(np.argmin(np.linalg.norm(current - path[i], axis=1)))
            b = int(np.argmin(np.linalg.norm(current - path[j], axis=1)))
            if b - a < 2:
                continue
            candidate = np.concatenate([current[: a + 1], current[b:]])
            caps = timer.tool_caps(candidate, slow_start, slow_end)
            _, samples = path_timer(candidate, timer.v_max, timer.a_max, caps, timer.tick)
            if len(samples) >= len(best):
                continue
            samples = np.array(samples)
            samples[0], samples[-1] = block.q[0], block.q[-1]
            if self.clear(arm, samples):
                best = samples
        return None if best is block.q else best

    def clear(self, arm: int, q_arm: FloatArray) -> bool:
        """Whether arm ``arm`` moving along ``q_arm`` from the end of its timeline sweeps clear
        of the world there, the other arms standing where they are at that tick."""
        k0 = self.horizon(arm)
        q = np.concatenate([self.rows(a, k0, k0) for a in self.arms], axis=1)
        q = np.repeat(q, len(q_arm), axis=0)
        q[:, self.columns[arm]] = q_arm
        self.sweep.reset([e for e in self.events if e.tick <= k0])
        return self.sweep.run(k0, q, []) is None


def schedule_timelines(
    plan: PlanFile,
    instance: Instance,
    scene: Scene,
    options: ScheduleOptions,
    timelines: TimelineOptions | None = None,
) -> Schedule:
    """``plan`` executed with one timeline per arm (see the module docstring); the input
    plan (``asynchronous`` False, with the reason) when no schedule is found or it is not
    shorter. ``options.timer`` is required for shortcuts (without it none are tried)."""
    shortcuts = timelines or TimelineOptions()
    if options.timer is None:
        shortcuts = dataclasses.replace(shortcuts, tries=0)
    retimers = [retimer(scene, i, options) for i in range(len(scene.arms))]
    blocks = [
        arm_blocks(plan, scene, i, options.tick, options.retime, retimers[i])
        for i in range(len(scene.arms))
    ]
    sweep = WorldSweep(instance, scene, options.max_tcp_step)
    after = dependencies(plan, instance, sweep)
    limited = dataclasses.replace(options, max_checks=shortcuts.max_checks)
    placement = Timelines(plan, blocks, sweep, limited, after, retimers, shortcuts)
    try:
        result = placement.run()
    except NoPlacement as exc:
        return Schedule(
            plan,
            False,
            plan.duration,
            None,
            "timelines",
            str(exc),
            sweep.checks,
            placement.figures(),
        )
    figures = placement.figures()
    limit = check_timeline(result, scene, options.dwell)
    if limit is not None:  # by construction this does not happen
        why = f"{limit.kind} at t={limit.t:.3f} s: {limit.message}"
        return Schedule(plan, False, plan.duration, None, "timelines", why, sweep.checks)
    if result.duration >= plan.duration:
        why = f"not shorter ({result.duration:.2f} s >= {plan.duration:.2f} s)"
        return Schedule(
            plan, False, plan.duration, result.duration, "timelines", why, sweep.checks, figures
        )
    return Schedule(
        result, True, plan.duration, result.duration, "timelines", "", sweep.checks, figures
    )


__all__ = ["TimelineOptions", "Timelines", "dependencies", "schedule_timelines"]
