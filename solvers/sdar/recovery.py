"""Dead-end recovery: evict resting objects that leave an object no grasp, recursively.

When no candidate step works, a remaining object may be boxed in: no arm grasps it where it
rests, or at its goal (whose footprint is free), while its neighbours rest where they do. The
IK stream, asked without some of the other resting objects, finds a minimal set of them whose
absence gives it a grasp (:meth:`Recovery.blockers`): every resting object may be in it (at
its goal, on a buffer or at its start), the objects at their goals last, since evicting one
costs two extra moves. A member that can be grasped where it rests is sent to a buffer (with
the object it unblocks when that goes to its goal and one eviction suffices); a member that
cannot is itself boxed in, and the same search runs for it, down to ``max_depth`` levels.

An evicted object does not come back to its goal before the object it made room for has left
the pose where it was boxed in (and, when that pose is its goal, has come back to it):
otherwise the eviction would be undone before it served (:class:`Deferral`).

Before any eviction, when some remaining object is boxed in (or no arm holds it with one of
the first grasps both where it rests and at its goal, :meth:`Recovery.carried`), the solver
tries the candidate steps toward the goals once more with the first ``pair_grasps`` grasps of
each object instead of the first ``grasps`` (:meth:`Recovery.wider`): an object whose few
grasps all meet a neighbour, at its pose or at its goal, often has one among the moderate tilts
that come after them (a 7-DoF arm's wrist, larger than the UR5e's, meets its neighbours
sooner), and a grasp costs no extra moves where an eviction costs two. Evicting first let two
such objects evict each other in turn (each boxed in at its goal by the other) until the
eviction budget ran out.

An object that is graspable where it rests and at its goal, but with no grasp in common (not
:meth:`Recovery.carried`), is not boxed in, so no eviction helps it; if more grasps do not
either, it is regrasped through a buffer (a ``regrasp`` step, one extra move): it goes to a
buffer from which some arm carries it to its goal with one of the first grasps
(:meth:`Recovery.buffer_clear` keeps only such buffers), picked there with another grasp than
the one that put it down.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from sdar_tamp.language.formula_model import Atom
from sdar_tamp.logs import get_logger
from solvers.sdar.budget import Deadline
from solvers.sdar.cache import StreamCache
from solvers.sdar.tasks import Move, Step, TaskView

if TYPE_CHECKING:
    from solvers.sdar.options import SdarOptions

LOG = get_logger(__name__)
#: Rank of a regrasp among the recovery's candidates: after the evictions that free a boxed-in
#: remaining object directly (ranks 0 to 2), level with the first of those one level deeper.
REGRASP_RANK = 3


@dataclass(frozen=True)
class Boxed:
    """``obj`` has no grasp at ``pose`` while the objects resting there (but ``lifted``) stay."""

    obj: str
    pose: str
    lifted: frozenset[str] = frozenset()


@dataclass
class Deferral:
    """An evicted object waits for ``target``, boxed in at ``pose``: released once ``target``
    has left ``pose`` and, when ``pose`` is the goal of ``target``, is back at it."""

    target: str
    pose: str
    left: bool = False

    def update(self, current: Mapping[str, str], goal: str) -> bool:
        """Note where ``target`` is now; ``True`` once the deferral is over."""
        here = current.get(self.target)
        if here != self.pose:
            self.left = True
        return self.left and (self.pose != goal or here == goal)


class Recovery:
    """The evictions of a run: how many were executed, and which evicted objects wait for
    which boxed-in ones. ``max_depth``: levels of boxed-in blockers searched below the boxed-in
    remaining object (0: only objects that can be grasped where they rest are evicted)."""

    def __init__(
        self,
        cache: StreamCache,
        options: SdarOptions,
        goals: Mapping[str, str],
        arms: Sequence[str],
        deadline: Deadline,
        max_depth: int = 3,
    ) -> None:
        if max_depth < 0:
            raise ValueError(f"max_depth must be >= 0, got {max_depth}")
        self.cache = cache
        self.options = options
        self.goals = goals
        self.arms = tuple(arms)
        self.deadline = deadline
        self.max_depth = max_depth
        self.evictions = 0
        self.deferred: dict[str, list[Deferral]] = {}  # evicted object -> what it waits for
        self._reasons: dict[tuple[Move, ...], tuple[tuple[str, Boxed], ...]] = {}
        self._regrasps: dict[tuple[Move, ...], str] = {}  # regrasp step -> its object
        self._boxed_in: dict[str, str] = {}  # boxed object -> where it rested then

    @property
    def budget_left(self) -> bool:
        """Fewer evictions so far than twice the number of objects."""
        return self.evictions < 2 * len(self.goals)

    def wider(self, view: TaskView | None = None) -> SdarOptions | None:
        """The options of the attempt before an eviction: every move searched among the first
        ``pair_grasps`` grasps of its object instead of the first ``grasps``; ``None`` when
        that is no wider or (given the ``view``) when no remaining object is boxed in
        (:meth:`boxed`) with the first grasps: then more grasps are not what is missing."""
        opt = self.options
        if opt.pair_grasps <= opt.grasps:
            return None
        if view is not None:
            current = self.cache.current_poses()
            if all(
                self.boxed(o, view, current) is None and self.carried(o, view, current)
                for o in view.remaining
            ):
                return None
        return replace(opt, grasps=opt.pair_grasps)

    def carried(self, obj: str, view: TaskView, current: Mapping[str, str]) -> bool:
        """Some arm holds ``obj`` with one of the first grasps both where it rests and at its
        goal (the other objects resting as they do); also ``True`` when something's footprint
        is at its goal (then the goal is not what is in question). A move carries its object
        with one grasp, so an object graspable where it rests with some grasps and at its goal
        with others (neither :meth:`boxed`) cannot be moved to its goal either."""
        if view.blockers(obj):
            return True
        cache, voc = self.cache, self.cache.voc
        here, goal = current[obj], self.goals[obj]
        resting = cache.fluents(voc.atpose)
        after = cache.fluents(voc.atpose, without=frozenset((obj,)))
        grasps = cache.outputs(voc.grasp, (obj,), self.options.grasps)
        return any(
            cache.outputs(voc.ik, (arm, obj, here, g), 1, resting)
            and cache.outputs(voc.ik, (arm, obj, goal, g), 1, after)
            for arm in self.arms
            for (g,) in grasps
        )

    # -- candidates ---------------------------------------------------------------------------
    def candidates(self, view: TaskView) -> list[Step]:
        """Evictions that give a boxed-in remaining object a grasp, or (deeper) give a grasp to
        a boxed-in object in the way of one; best first (see the module docstring)."""
        self._reasons = {}
        self._regrasps = {}
        self._boxed_in = {}
        ranked: list[tuple[int, int, Step]] = []
        current = self.cache.current_poses()
        self._boxed_in = dict(current)
        done = view.done
        for obj in view.remaining:
            if self.deadline.passed():
                break
            boxed = self.boxed(obj, view, current)
            if boxed is not None:
                self._unblock(boxed, current, done, 0, (obj,), ranked)
            elif not self.carried(obj, view, current):
                step = Step((Move(obj, True),), "regrasp", REGRASP_RANK)
                self._regrasps[step.moves] = obj
                ranked.append((REGRASP_RANK, len(ranked), step))
        ranked.sort(key=lambda item: item[:2])
        seen: set[tuple[Move, ...]] = set()
        out: list[Step] = []
        for _, _, step in ranked:
            if step.moves not in seen:
                seen.add(step.moves)
                out.append(step)
        return out

    def boxed(self, obj: str, view: TaskView, current: Mapping[str, str]) -> Boxed | None:
        """``obj`` cannot be grasped where it rests, or at its goal when nothing's footprint
        is in the way there; ``None`` when neither holds."""
        here = Boxed(obj, current[obj])
        if not self.reachable(here):
            return here
        at_goal = Boxed(obj, self.goals[obj], frozenset((obj,)))
        if not view.blockers(obj) and not self.reachable(at_goal):
            return at_goal
        return None

    def _unblock(
        self,
        boxed: Boxed,
        current: Mapping[str, str],
        done: frozenset[str],
        depth: int,
        chain: tuple[str, ...],
        out: list[tuple[int, int, Step]],
    ) -> None:
        members = self.blockers(boxed, current, done, chain)
        show = self.cache.show
        where = "at its goal" if boxed.lifted else "where it rests"
        if not members:
            LOG.debug("sdar: %s boxed in %s: no other objects make room", show(boxed.obj),
                      where)  # fmt: skip
            return
        order = len(out)
        free = [m for m in members if self.reachable(Boxed(m, current[m]))]
        LOG.debug("sdar: %s boxed in %s (depth %d) by %s; graspable: %s", show(boxed.obj),
                  where, depth, ", ".join(map(show, sorted(members))),
                  ", ".join(map(show, free)) or "none")  # fmt: skip
        base = 3 * depth
        pairs = len(self.arms) >= 2  # two-move evictions need two arms
        for m in free:
            why = ((m, boxed),)
            if pairs and depth == 0 and boxed.lifted and len(members) == 1:
                self._add(out, base, order, Step((Move(boxed.obj), Move(m, True)), "evict"), why)
            self._add(out, base + 1, order, Step((Move(m, True),), "evict"), why)
        if pairs and len(free) >= 2:
            a, b = free[:2]
            step = Step((Move(a, True), Move(b, True)), "evict")
            self._add(out, base + 2, order, step, ((a, boxed), (b, boxed)))
        if depth >= self.max_depth:
            return
        for m in members:
            if m not in free and not self.deadline.passed():
                self._unblock(Boxed(m, current[m]), current, done, depth + 1, (*chain, m), out)

    def _add(
        self,
        out: list[tuple[int, int, Step]],
        rank: int,
        order: int,
        step: Step,
        why: tuple[tuple[str, Boxed], ...],
    ) -> None:
        out.append((rank, order, Step(step.moves, step.kind, rank)))
        self._reasons.setdefault(step.moves, why)

    def blockers(
        self,
        boxed: Boxed,
        current: Mapping[str, str],
        done: frozenset[str],
        chain: Sequence[str] = (),
    ) -> frozenset[str]:
        """A minimal set of resting objects (none of ``chain``) whose absence gives
        ``boxed.obj`` a grasp at ``boxed.pose``; empty when there is none (or no need).

        Every candidate starts away; one by one each is put back and stays back when the grasp
        remains possible: the objects at their goals (``done``) are put back first, so the set
        holds as few of them as the others allow. Each member is needed: with it back (and the
        others of the set away) no arm has a grasp.
        """
        keep = set(chain) | {boxed.obj} | set(boxed.lifted)
        movable = sorted((o for o in current if o not in keep), key=lambda o: (o not in done, o))
        away = set(boxed.lifted) | set(movable)
        if not self.reachable(Boxed(boxed.obj, boxed.pose, frozenset(away))):
            return frozenset()  # not even alone on the table (out of reach)
        for o in movable:
            if self.deadline.passed():
                return frozenset()
            trial = frozenset(away - {o})
            if self.reachable(Boxed(boxed.obj, boxed.pose, trial)):
                away.discard(o)
        return frozenset(away - set(boxed.lifted))

    def reachable(self, boxed: Boxed, fluents: tuple[Atom, ...] | None = None) -> bool:
        """Some arm grasps ``boxed.obj`` at ``boxed.pose`` with some grasp while the objects
        in ``boxed.lifted`` are away (among the ``atpose`` atoms ``fluents``, by default the
        current ones)."""
        cache, voc = self.cache, self.cache.voc
        if fluents is None:
            fluents = cache.fluents(voc.atpose, without=boxed.lifted)
        grasps = cache.outputs(voc.grasp, (boxed.obj,), self.options.grasps)
        return any(
            cache.outputs(voc.ik, (arm, boxed.obj, boxed.pose, g), 1, fluents)
            for arm in self.arms
            for (g,) in grasps
        )

    def buffer_clear(self, moves: tuple[Move, ...], obj: str, pose: str) -> bool:
        """``obj``, evicted by the step of ``moves`` (one of the last :meth:`candidates`) to
        ``pose``, does not box in again the object it makes room for (``True`` for the
        buffers of other steps)."""
        if self._regrasps.get(moves) == obj:
            return self.carries_from(obj, pose)
        lifted = {m.obj for m in moves}
        voc = self.cache.voc
        for evicted, boxed in self._reasons.get(moves, ()):
            if evicted != obj:
                continue
            away = frozenset(lifted | boxed.lifted)
            fluents = tuple(sorted(
                (*self.cache.fluents(voc.atpose, without=away), Atom(voc.atpose, (obj, pose))),
                key=str,
            ))  # fmt: skip
            if not self.reachable(boxed, fluents):
                return False
        return True

    def carries_from(self, obj: str, pose: str) -> bool:
        """Some arm holds ``obj``, put down at ``pose`` (the other objects resting as they do
        now), with one of the first grasps both there and at its goal."""
        cache, voc = self.cache, self.cache.voc
        goal = self.goals[obj]
        others = cache.fluents(voc.atpose, without=frozenset((obj,)))
        there = tuple(sorted((*others, Atom(voc.atpose, (obj, pose))), key=str))
        grasps = cache.outputs(voc.grasp, (obj,), self.options.grasps)
        return any(
            cache.outputs(voc.ik, (arm, obj, pose, g), 1, there)
            and cache.outputs(voc.ik, (arm, obj, goal, g), 1, others)
            for arm in self.arms
            for (g,) in grasps
        )

    # -- execution ------------------------------------------------------------------------------
    def executed(self, step: Step) -> None:
        """``step``, one of the last :meth:`candidates`, was executed: its evicted objects now
        wait for the objects they made room for."""
        self.evictions += 1
        for obj, boxed in self._reasons.get(step.moves, ()):
            left = self._boxed_in.get(boxed.obj) != boxed.pose  # boxed in at its goal
            self.deferred.setdefault(obj, []).append(Deferral(boxed.obj, boxed.pose, left))

    def allowed(self, candidates: Sequence[Step]) -> list[Step]:
        """Candidates that bring no waiting evicted object to its goal (all of them when every
        candidate would)."""
        current = self.cache.current_poses()
        for obj in list(self.deferred):
            waits = [d for d in self.deferred[obj] if not d.update(current, self.goals[d.target])]
            if waits:
                self.deferred[obj] = waits
            else:
                del self.deferred[obj]
        if self.deferred:
            show = self.cache.show
            waiting = (f"{show(o)} for {', '.join(show(d.target) for d in ds)}"
                       for o, ds in self.deferred.items())  # fmt: skip
            LOG.debug("sdar: evicted objects waiting: %s", "; ".join(waiting))
        return [
            s
            for s in candidates
            if not any(not m.to_buffer and m.obj in self.deferred for m in s.moves)
        ] or list(candidates)
