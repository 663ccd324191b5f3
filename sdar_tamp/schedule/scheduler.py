"""Asynchronous execution: a synchronous plan of k arms re-scheduled so each arm runs on its own.

In a synchronous plan a step lasts as long as the slowest arm's motion and one arm's gripper
dwell stops the other arms too. :func:`schedule_async` cuts each arm's timeline into blocks
(:mod:`sdar_tamp.schedule.pieces`: rest-to-rest motions, each re-timed for its arm alone by
:mod:`sdar_tamp.schedule.retiming` and optionally ending in a gripper event and the arm's own
dwell) and places them on a new common timeline of ``tick`` [s], group by group (the blocks
that overlapped in the synchronous plan, :func:`groups`), each block of a group at the
earliest tick that

* follows the arm's previous block (and its dwell),
* keeps the cross-arm order of gripper events (``order="objects"``: the events on one object,
  the later one at least a dwell after the earlier; ``order="events"``: every event keeps its
  place relative to the other arms' events),
* lets the block end no later than it ended in the synchronous plan,
* and passes the replay (:mod:`sdar_tamp.schedule.sweep`) of everything from the arm's last
  block to the end of every arm's timeline: no collision between any two arms, their held
  objects, the table and the resting objects where they rest at that time; released objects
  land on free spots. An arm whose next block is not placed yet stands where its last block left it.

When a block finds no start, the group is taken back and tried with each other arm leading in
turn (:meth:`Placement.reorderings`; for two arms: the other arm first); when that fails too,
the group goes as in the synchronous plan (every arm at its synchronous pace and offsets),
shifted as early as its arms allow: in the same configurations and world as there, so it
passes. Every stretch of the result is replayed once every arm is fixed there, so the
schedule is collision-free at the validator's points. Blocks start and end at rest and
are sampled on the common grid, so the limits hold. The result is kept only when shorter than
the synchronous plan (else the next ordering is tried, and at last the synchronous plan kept).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_file import GRIPPER_DWELL, MAX_DT, PlanEvent, PlanFile, StepRecord
from sdar_tamp.plan_rules import check_timeline
from sdar_tamp.schedule.pieces import Block, arm_blocks, arm_columns
from sdar_tamp.schedule.retiming import ArmRetimer, PathTimer
from sdar_tamp.schedule.sweep import Conflict, TimedEvent, WorldSweep
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.kinematics import ArmKinematics
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray

ORDERS = ("objects", "events")


@dataclass(frozen=True)
class ScheduleOptions:
    """``tick`` [s]: the common grid (at most the plan format's 0.02 s); ``retime``: play each
    motion as fast as its arm's limits allow (else at its synchronous pace); ``orders``: the
    cross-arm event orderings to try, in turn; ``max_tcp_step`` [m]: the replay's resolution;
    ``max_wait`` [s]: the longest delay tried for one block; ``timer``: the time-optimal
    path timing each arm's motions are re-timed with (None: uniformly faster, see
    :mod:`sdar_tamp.schedule.retiming`); ``straight`` [m] and ``grasp_speed`` [m/s]: the slow
    tool travel at a gripper event that re-timing keeps; ``max_checks``: the collision
    queries the search may make; past them the remaining steps keep their synchronous pace."""

    tick: float = MAX_DT
    retime: bool = True
    orders: tuple[str, ...] = ORDERS
    max_tcp_step: float = 0.005
    dwell: float = GRIPPER_DWELL
    max_wait: float = 20.0
    max_checks: int = 40_000
    timer: PathTimer | None = None
    straight: float = 0.02
    grasp_speed: float = 0.25

    def __post_init__(self) -> None:
        if not (math.isfinite(self.tick) and 0.0 < self.tick <= MAX_DT):
            raise ParameterError(f"tick: expected a time in (0, {MAX_DT}] s, got {self.tick!r}")
        if isinstance(self.max_checks, bool) or not (
            isinstance(self.max_checks, int) and self.max_checks > 0
        ):
            raise ParameterError(f"max_checks: expected an integer > 0, got {self.max_checks!r}")
        for name in ("straight", "grasp_speed"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ParameterError(f"{name}: expected a finite number > 0, got {value!r}")
        for name in ("max_tcp_step", "dwell", "max_wait"):
            value = getattr(self, name)
            positive = value > 0.0 or name != "max_tcp_step"
            if not (math.isfinite(value) and value >= 0.0 and positive):
                raise ParameterError(
                    f"{name}: expected a finite number >= 0 (> 0 for max_tcp_step), got {value!r}"
                )
        bad = [o for o in self.orders if o not in ORDERS]
        if bad or not self.orders:
            raise ParameterError(f"orders: expected some of {list(ORDERS)}, got {self.orders!r}")


@dataclass(frozen=True)
class Schedule:
    """The outcome: ``plan`` (the asynchronous one when it is shorter, else the input),
    ``asynchronous``, both durations [s] (``async_duration`` None when no schedule was found),
    the ``order`` that worked, ``reason`` (why the synchronous plan was kept), ``checks``
    (collision queries made) and ``figures`` (what the scheduler measured, by name)."""

    plan: PlanFile
    asynchronous: bool
    sync_duration: float
    async_duration: float | None
    order: str
    reason: str
    checks: int
    figures: tuple[tuple[str, float], ...] = ()


@dataclass(frozen=True, eq=False)
class Entry:
    """A block to place, as samples ``q`` ``(n + 1, k)`` (the arm's ``k`` joints), ``offset``
    ticks after the start
    of its group."""

    arm: int
    block: Block
    q: FloatArray
    offset: int


def _events_of(entries: list[Entry], new: list[TimedEvent]) -> list[TimedEvent | None]:
    """The new event of each entry (None for an entry without one)."""
    found = {id(e.event): e for e in new}
    return [found.get(id(x.block.event)) if x.block.event is not None else None for x in entries]


class NoPlacement(Exception):
    def __init__(self, block: Block, conflict: Conflict | None, detail: str) -> None:
        super().__init__(detail)
        self.block, self.conflict = block, conflict


def schedule_async(
    plan: PlanFile, instance: Instance, scene: Scene, options: ScheduleOptions | None = None
) -> Schedule:
    """Re-schedule the synchronous ``plan`` of ``instance`` for asynchronous execution (see the
    module docstring). The plan is assumed valid for ``instance`` in ``scene``."""
    options = options or ScheduleOptions()
    blocks = [
        arm_blocks(plan, scene, i, options.tick, options.retime, retimer(scene, i, options))
        for i in range(len(scene.arms))
    ]
    sweep = WorldSweep(instance, scene, options.max_tcp_step)
    reasons = []
    for order in options.orders:
        try:
            result = Placement(plan, blocks, sweep, options, order).run()
        except NoPlacement as exc:
            reasons.append(f"order {order}: {exc}")
            continue
        limit = check_timeline(result, scene, options.dwell)
        if limit is not None:  # by construction this does not happen
            reasons.append(f"order {order}: {limit.kind} at t={limit.t:.3f} s: {limit.message}")
            continue
        if result.duration >= plan.duration:
            reason = f"not shorter ({result.duration:.2f} s >= {plan.duration:.2f} s)"
            return Schedule(
                plan, False, plan.duration, result.duration, order, reason, sweep.checks
            )
        return Schedule(result, True, plan.duration, result.duration, order, "", sweep.checks)
    return Schedule(plan, False, plan.duration, None, "", "; ".join(reasons), sweep.checks)


def retimer(scene: Scene, arm: int, options: ScheduleOptions) -> ArmRetimer:
    """The re-timing of arm ``arm`` (scene order) the ``options`` ask for."""
    spec = scene.arms[arm]
    return ArmRetimer(
        ArmKinematics.from_scene(scene, spec.name),
        np.array(spec.velocity_limit),
        np.array(spec.acceleration_limit),
        options.tick,
        options.timer,
        options.straight,
        options.grasp_speed,
    )


def groups(blocks: list[list[Block]]) -> list[list[Block]]:
    """Every arm's blocks in groups that overlapped (or touched) in the synchronous plan, in
    time order; a group's blocks in the order they ended there."""
    ordered = sorted((b for arm in blocks for b in arm), key=lambda b: (b.sync_start, b.arm))
    out: list[list[Block]] = []
    end = -math.inf
    for b in ordered:
        if out and b.sync_start <= end + 1e-9:
            out[-1].append(b)
            end = max(end, b.sync_key)
        else:
            out.append([b])
            end = b.sync_key
    return [sorted(g, key=lambda b: (b.sync_key, b.arm)) for g in out]


class Placement:
    """The greedy placement of every arm's blocks for one event ordering."""

    def __init__(
        self,
        plan: PlanFile,
        blocks: list[list[Block]],
        sweep: WorldSweep,
        options: ScheduleOptions,
        order: str,
    ) -> None:
        self.plan, self.blocks, self.sweep, self.order = plan, blocks, sweep, order
        self.tick = options.tick
        self.dwell = math.ceil(options.dwell / options.tick - 1e-9)
        self.max_wait = math.ceil(options.max_wait / options.tick)
        self.max_checks = options.max_checks
        self.arms = range(len(plan.arms))
        self.columns = [arm_columns(plan, i) for i in self.arms]
        self.traj: list[list[FloatArray]] = [[plan.q[0, self.columns[i]]] for i in self.arms]
        self.events: list[TimedEvent] = []
        self.event_tick: dict[int, int] = {}  # id(sync event) -> tick
        self.steps: list[StepRecord] = []
        #: ticks between the starts tried by :meth:`place`
        self.stride = 1
        #: :meth:`place` gives up at a conflict after every other arm's timeline has ended
        #: (those arms stand still from then on: a later start meets the same conflict)
        self.give_up_standing = False
        #: the last successful :meth:`place`: its start's delay past the earliest [ticks] and
        #: the conflict met at the earliest start (None: placed there)
        self.delay = 0
        self.delayed_by: Conflict | None = None

    def horizon(self, arm: int) -> int:
        return len(self.traj[arm]) - 1

    def run(self) -> PlanFile:
        """Place the blocks group by group (:func:`groups`: the blocks that overlapped in the
        synchronous plan), each block of a group on its own, in the order the blocks ended
        there, at the earliest tick that lets its motion end no later than it did there. When
        a block finds no such start, the group's blocks placed so far are taken back and the
        whole group goes at once, every block at its synchronous pace and offset (a copy of
        the synchronous plan's stretch, shifted earlier)."""
        for group in groups(self.blocks):
            mark = self.mark()
            searching = self.sweep.checks < self.max_checks
            if searching and any(self.alone(order) for order in self.reorderings(group)):
                continue
            self.undo(mark)
            first = min(b.sync_index for b in group)
            self.place([Entry(b.arm, b, b.q_sync, b.sync_index - first) for b in group])
        return self.assemble()

    def alone(self, group: list[Block]) -> bool:
        """Place the blocks of ``group`` one by one, in this order, each ending no later than
        in the synchronous plan; False (with the group's placements taken back) when one finds
        no start."""
        mark = self.mark()
        try:
            for block in group:
                latest = math.ceil(block.sync_end / self.tick - 1e-9) - block.motion_ticks
                self.place([Entry(block.arm, block, block.q, 0)], latest)
        except NoPlacement:
            self.undo(mark)
            return False
        return True

    def reorderings(self, group: list[Block]) -> list[list[Block]]:
        """The orders :meth:`run` tries ``group`` in: as it is, then (for a group of more than
        one block) with each other arm leading in turn, the arms' order rotated (each arm's
        blocks in order). A rotation that breaks the order of the events is replaced by
        ``group`` itself (tried again: the searches and their collision checks are those of
        the two-arm scheduler, where the one rotation puts the other arm first)."""
        out = [group]
        if len(group) < 2:
            return out
        arms = list(dict.fromkeys(b.arm for b in group))
        for r in range(1, max(2, len(arms))):
            k = r % len(arms)
            moved = [b for arm in arms[k:] + arms[:k] for b in group if b.arm == arm]
            timed = [b.event for b in moved if b.event is not None]
            broken = any(
                self.must_follow(e, o) for i, e in enumerate(timed) for o in timed[i + 1 :]
            )
            out.append(group if broken else moved)
        return out

    def mark(self) -> tuple[list[int], list[TimedEvent], dict[int, int], int]:
        """What :meth:`undo` restores."""
        lengths = [len(traj) for traj in self.traj]
        return lengths, list(self.events), dict(self.event_tick), len(self.steps)

    def undo(self, mark: tuple[list[int], list[TimedEvent], dict[int, int], int]) -> None:
        """Take back every placement since ``mark``."""
        lengths, events, event_tick, steps = mark
        for traj, n in zip(self.traj, lengths, strict=True):
            del traj[n:]
        self.events, self.event_tick = list(events), dict(event_tick)  # a mark serves again
        del self.steps[steps:]

    def ready(self, block: Block) -> bool:
        """Whether the events ``block``'s event must follow are placed."""
        e = block.event
        return e is None or all(
            id(o) in self.event_tick for o in self.plan.events if self.must_follow(e, o)
        )

    def must_follow(self, e: PlanEvent, other: PlanEvent) -> bool:
        """Whether event ``e`` must come after ``other`` of another arm."""
        if other.arm == e.arm or other.t >= e.t:
            return False
        return self.order == "events" or other.object == e.object

    def earliest(self, entry: Entry) -> int:
        """The first start tick of the group the arm's horizon and the event orderings
        allow for ``entry``."""
        s = self.horizon(entry.arm)
        e = entry.block.event
        if e is not None:
            for other in self.plan.events:
                if self.must_follow(e, other) and id(other) in self.event_tick:
                    same = other.object == e.object
                    k = self.event_tick[id(other)] + (self.dwell if same else 0)
                    s = max(s, k - (len(entry.q) - 1))
        return s - entry.offset

    def rows(self, arm: int, k0: int, k1: int) -> FloatArray:
        """Arm ``arm``'s configurations ``(k1 - k0 + 1, k)`` at ticks ``k0 .. k1`` (standing
        at its last one after its horizon)."""
        traj = self.traj[arm]
        idx = np.minimum(np.arange(k0, k1 + 1), len(traj) - 1)
        return np.array([traj[i] for i in idx])

    def length(self, entry: Entry) -> int:
        """Ticks of the entry's motion and of the dwell after its event."""
        return len(entry.q) - 1 + (self.dwell if entry.block.event is not None else 0)

    def place(self, entries: list[Entry], latest: int | None = None) -> None:
        """Place the blocks of ``entries`` (an arm's in order, apart by their offsets) at the
        earliest common start ``s`` (each at ``s + offset``), at most ``latest`` when given,
        whose replay passes; raises :class:`NoPlacement`."""
        arms = [e.arm for e in entries]
        k0 = min(self.horizon(a) for a in arms)
        start = max(self.earliest(e) for e in entries)
        stop = start + self.max_wait
        if latest is not None:
            stop = min(stop, max(start, latest))
        before = [e for e in self.events if e.tick < k0]
        later = [e for e in self.events if e.tick >= k0]
        conflict: Conflict | None = None
        until = start - 1  # starts up to this one are passed over: they fail (:meth:`skipped`)
        for s in range(start, stop + 1, self.stride):
            if s <= until:
                continue
            ends = [s + e.offset + self.length(e) for e in entries]
            k1 = max(*ends, *(self.horizon(a) for a in self.arms))
            q = np.concatenate([self.rows(a, k0, k1) for a in self.arms], axis=1)
            new: list[TimedEvent] = []
            for e in sorted(entries, key=lambda e: (e.arm, e.offset)):
                begin = s + e.offset
                cols = self.columns[e.arm]
                q[begin - k0 : begin - k0 + len(e.q), cols] = e.q
                q[begin - k0 + len(e.q) :, cols] = e.q[-1]
                if e.block.event is not None:
                    new.append(TimedEvent(begin + len(e.q) - 1, e.block.event, e.q[-1]))
            events = sorted([*later, *new], key=lambda e: e.tick)
            self.sweep.reset(before)
            conflict = self.sweep.run(k0, q, events)
            if s == start:
                self.delayed_by = conflict
            if conflict is None:
                self.delay = s - start
                placed = zip(entries, ends, _events_of(entries, new), strict=True)
                for e, end, timed in sorted(placed, key=lambda x: (x[0].arm, x[0].offset)):
                    self.commit(e, s + e.offset, q[: end - k0 + 1, self.columns[e.arm]], k0, timed)
                return
            if conflict.tick < s:  # while an arm waits for its start: later is no better
                break
            others = [self.horizon(a) for a in self.arms if a not in arms]
            if self.give_up_standing and conflict.tick >= max(others, default=0):
                break
            if all(s > self.horizon(a) for a in self.arms if a not in arms):
                break  # the other arms stand still from now on: nothing changes
            until = s + self.skipped(entries, s, conflict.tick)
            passed = s + (until - s) // self.stride * self.stride  # the last start passed over
            if passed > s and all(passed > h for h in others):
                break  # a start passed over would have ended the search there
        block = entries[0].block
        detail = (
            f"no start for a block of {self.plan.arm_names[entries[0].arm]} "
            f"(synchronous t = {block.sync_start:.2f}..{block.sync_end:.2f} s)"
        )
        if conflict is not None:
            detail += f"; at t = {conflict.tick * self.tick:.2f} s: {conflict.message}"
        raise NoPlacement(block, conflict, detail)

    def skipped(self, entries: list[Entry], s: int, tick: int) -> int:
        """Ticks of the starts after ``s`` that :meth:`place` passes over, all of which fail:
        a single block whose replay from start ``s`` met a conflict at ``tick`` after its
        motion (its arm standing where the motion ends, as it does at that tick from every
        start up to ``tick`` minus the motion's ticks, in the same world: the other arms'
        trajectories and events are fixed, the block's own event is earlier)."""
        if len(entries) != 1:
            return 0
        motion = len(entries[0].q) - 1
        last = tick - motion - entries[0].offset  # the last start whose arm stands at ``tick``
        return max(0, last - s)

    def commit(
        self, entry: Entry, s: int, rows: FloatArray, k0: int, timed: TimedEvent | None
    ) -> None:
        horizon = self.horizon(entry.arm)
        self.traj[entry.arm].extend(rows[horizon - k0 + 1 :])
        if timed is not None:
            self.events.append(timed)
            self.events.sort(key=lambda e: e.tick)
            self.event_tick[id(timed.event)] = timed.tick
        st = entry.block.step
        if len(entry.q) > 1 and st is not None:
            t0, t1 = s * self.tick, (s + len(entry.q) - 1) * self.tick
            self.steps.append(StepRecord(t0, t1, st.level, st.objects, st.kind))

    def assemble(self) -> PlanFile:
        n = max(self.horizon(a) for a in self.arms)
        q = np.concatenate([self.rows(a, 0, n) for a in self.arms], axis=1)
        t = np.arange(n + 1, dtype=np.float64) * np.float64(self.tick)
        events = tuple(
            PlanEvent(float(t[e.tick]), e.event.arm, e.event.type, e.event.object,
                      e.event.T_tcp_object)
            for e in self.events
        )  # fmt: skip
        metrics = self.plan.metrics.updated(
            {
                "execution": "async",
                "execution_time": float(t[-1]),
                "execution_time_sync": self.plan.duration,
            }
        )
        steps = tuple(sorted(self.steps, key=lambda s: (s.t_start, s.t_end)))
        return dataclasses.replace(self.plan, t=t, q=q, events=events, metrics=metrics, steps=steps)
