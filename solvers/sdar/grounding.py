"""Grounding of candidate steps: grasps, IK at both ends, buffers and cell configurations.

For a candidate step and an assignment of arms, :class:`Grounder` asks the streams for a few
(grasp, pick IK, target, place IK) options per move, combines them into collision-free cell
configurations (every arm; an arm without a move waits at home), or, for the one-arm-at-a-time
motion planner, a sequence of gripper events with the other arms at home, and ranks the
groundings by the task planner's rank and then by the estimated motion time. Groundings that
failed before are skipped (see :class:`~solvers.sdar.attempts.TabuLists`); with more than two
arms, options are checked in pairs of arms and steps known not to ground are skipped
(:mod:`~solvers.sdar.k_grounding`).

The assignments of arms to a step's moves are :mod:`~solvers.sdar.assignment`'s. The
options of a step of ``m > 2`` moves are cut so that the checks of a stage stay within
:data:`MAX_COMBINATIONS`: per pair of moves when its options are checked in pairs of arms
(:meth:`~solvers.sdar.k_grounding.KArmChecks.pairwise`: as many options per move as a
two-move step's expanded stage, the combinations then only looked up), else per
combination; and with more than two arms, among groundings of one rank, those bringing more
objects to their goals come first (then the estimated motion time).
"""

from __future__ import annotations

import itertools
from collections import Counter
from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from sdar_tamp.language.formula_model import Atom
from solvers.sdar.arm_pairs import AT_PICK, AT_PLACE
from solvers.sdar.assignment import ArmAssigner
from solvers.sdar.attempts import MotionMode, TabuLists
from solvers.sdar.budget import Deadline
from solvers.sdar.cache import StreamCache
from solvers.sdar.free_pairs import FreePairs
from solvers.sdar.k_grounding import KArmChecks
from solvers.sdar.move_option import Option
from solvers.sdar.one_arm import one_arm_order
from solvers.sdar.report import Failures
from solvers.sdar.tasks import Layout, Move, Step

if TYPE_CHECKING:
    from solvers.sdar.options import SdarOptions


BufferCheck = Callable[[tuple[Move, ...], str, str], bool]
#: ``(step, arms, mode)`` -> the family (the step's moves with these arms) is not grounded now
FamilyCheck = Callable[[Step, tuple[str, ...], MotionMode], bool]


@dataclass(frozen=True)
class Event:
    """One gripper action of a one-arm-at-a-time execution, at ``conf``: the acting arm at
    its pick or place configuration, the other arm at home."""

    index: int  # into the step's moves
    pick: bool
    conf: str  # dual-arm configuration


@dataclass(frozen=True)
class Grounding:
    """A step with arms and options; ``d_pick`` / ``d_place``: the dual-arm configurations of
    the first and of the last gripper action."""

    step: Step
    arms: tuple[str, ...]
    options: tuple[Option, ...]
    d_pick: str
    d_place: str
    estimate: float
    sequence: tuple[Event, ...] = ()  # one arm at a time only


class Grounder:
    """Grounds candidate steps in the current arrangement of ``cache``."""

    def __init__(
        self,
        cache: StreamCache,
        options: SdarOptions,
        goals: Mapping[str, str],
        home: Mapping[str, str],
        tabu: TabuLists,
        failures: Failures,
        deadline: Deadline,
    ) -> None:
        self.cache = cache
        self.options = options
        self.goals = goals
        self.home = home
        self.tabu = tabu
        self.failures = failures
        self.deadline = deadline
        self._free = FreePairs(cache, goals, self._combine)
        self.buffer_check: BufferCheck | None = None
        """Keeps only the buffers it accepts for (the step's moves, object, buffer pose)."""
        self.skip_family: FamilyCheck | None = None
        """Assignments it answers True for are not grounded (they count as tried before:
        :mod:`~solvers.sdar.spending`)."""
        self.first_found = False
        """Stop at the first assignment of arms that grounds (the anytime finish)."""
        self.layout: Layout | None = None
        """With more than two arms: the current view's layout; assignments whose arms cross
        (:meth:`~solvers.sdar.tasks.Layout.conflicts`) come after the others."""
        self.k = KArmChecks(cache, options, goals, len(home), self._combine)
        """With more than two arms: pairwise checks and remembered failures."""
        self._tabu_met = False  # a combination was skipped as tried before
        self.assigner = ArmAssigner(
            cache, options, home, failures, lambda *args: self._move_options(*args)
        )

    def key(self, step: Step, arms: tuple[str, ...], combo: tuple[Option, ...]) -> Hashable:
        """The tabu key of a grounding in the current arrangement."""
        return (self.cache.fluents(self.cache.voc.atpose), step.moves, arms, combo)

    def select(self, candidates: Sequence[Step], mode: MotionMode) -> list[Grounding]:
        """Feasible groundings, best first: task-planner rank, then estimated motion time.
        Beyond the first ``choose_among`` groundings, up to ``peer_steps`` more candidates
        alike to the first grounded one (:meth:`Step.peer_of`) are grounded and compared."""
        found: list[Grounding] = []
        peers = 0  # candidates grounded as alike to the first one grounded
        for index, step in enumerate(candidates):
            if self.deadline.passed():
                break
            if found:
                peer = step.peer_of(found[0].step) and peers < self.options.peer_steps
                if not peer and (
                    step.rank > found[0].step.rank
                    or index >= self.options.candidates
                    or len(found) >= self.options.choose_among
                ):
                    break
                peers += peer
            why = self.k.skip(step)
            if why is not None:
                self.failures.unassigned(step, why)
                continue
            self._tabu_met = False
            grounded = len(found)
            for arms in self._assignments(step):
                if self.skip_family is not None and self.skip_family(step, arms, mode):
                    self._tabu_met = True
                    continue
                found.extend(self._ground(step, arms, mode))
                if self.first_found and len(found) > grounded:
                    break
            if not (len(found) > grounded or self._tabu_met or self.deadline.passed()):
                self.k.failed(step)
            if len(self.home) > 2:
                found.sort(key=lambda g: (g.step.rank, -g.step.progress, g.estimate))
            else:
                found.sort(key=lambda g: (g.step.rank, g.estimate))
        return found

    def _assignments(self, step: Step) -> list[tuple[str, ...]]:
        """Arms for the step's moves, in order (:mod:`~solvers.sdar.assignment`)."""
        return self.assigner.assignments(step, self.layout)

    def _ground(self, step: Step, arms: tuple[str, ...], mode: MotionMode) -> list[Grounding]:
        """Every grounding of ``step`` with ``arms`` not yet tried, cheapest estimate first:
        from ``options_per_move`` options per move, or from ``more_options`` when none of
        those combinations works (two arms reaching for neighbouring objects often collide
        with the first grasps and not with tilted ones), and for a two-move step at last
        from the first ``pair_grasps`` grasps, the stream's pair grasps included (two grippers
        placing touching objects at once need a compatible pair, often two grasps tilted away
        from each other; ``pair_kinds``), restricted to the grasps of :meth:`free_pairs`. A
        stage with more grasps is reached even when the earlier ones ran out of options."""
        lifted = frozenset(step.objects)
        opt = self.options
        stages = grounding_stages(step, opt, self.k.pairwise(step))
        found: list[Grounding] = []
        misses: Counter[str] = Counter()  # why combinations of options failed
        poses = self.cache.current_poses()
        for k, (limit, grasps) in enumerate(stages):
            allowed: Sequence[frozenset[str] | None] = [None] * len(step.moves)
            if grasps > opt.grasps:  # the pair search: only grasps of a pair that can work
                free = self.free_pairs(step, arms, grasps)
                if free is not None and not all(free):
                    misses[_NO_FREE_PAIR] += 1
                    break
                allowed = free or allowed
            if self.k.pairwise(step):
                remembered = self.k.pairs.meets(step, arms, (limit, grasps), poses)
                if remembered is not None:  # found at an earlier assignment or decision
                    misses[f"{remembered} (remembered)"] += 1
                    continue
            per_move = [
                self._move_options(a, m, lifted, limit, grasps, only, step.moves)
                for a, m, only in zip(arms, step.moves, allowed, strict=True)
            ]
            more_grasps = any(g > grasps for _, g in stages[k + 1 :])
            for a, m, options in zip(arms, step.moves, per_move, strict=True):
                if not options and not more_grasps:
                    target = "a buffer" if m.to_buffer else "its goal"
                    show = self.cache.show
                    self.failures.why(step, arms, f"no grasp with IK for {show(a)} at "
                                      f"{show(m.obj)} and at {target}")  # fmt: skip
                    return []
            if all(per_move):
                found = self._combinations(step, arms, per_move, mode, misses, (limit, grasps))
            exhausted = all(len(options) < limit for options in per_move)
            if found or (exhausted and not more_grasps):
                break  # a later stage offers nothing new once every grasp was tried
        if not found:
            self.failures.why(step, arms, _no_grounding(misses))
        return sorted(found, key=lambda g: g.estimate)

    def free_pairs(
        self, step: Step, arms: tuple[str, ...], grasps: int
    ) -> tuple[frozenset[str], ...] | None:
        """:class:`~solvers.sdar.free_pairs.FreePairs` of the step (None: not two goals)."""
        return self._free(step, arms, grasps)

    def _move_options(
        self,
        arm: str,
        move: Move,
        lifted: frozenset[str],
        limit: int,
        grasps: int,
        only: frozenset[str] | None = None,
        moves: tuple[Move, ...] = (),
    ) -> list[Option]:
        cache, voc, opt = self.cache, self.cache.voc, self.options
        p = cache.current_poses()[move.obj]
        resting = cache.fluents(voc.atpose)
        if move.to_buffer:
            targets = [out[0] for out in cache.outputs(voc.buffer, (move.obj,), opt.buffers,
                                                         resting)]  # fmt: skip
            if self.buffer_check is not None:
                targets = [t for t in targets if self.buffer_check(moves, move.obj, t)]
        else:
            targets = [self.goals[move.obj]]
        after = cache.fluents(voc.atpose, without=lifted)
        found: list[Option] = []
        for (g,) in cache.outputs(voc.grasp, (move.obj,), grasps):
            if only is not None and g not in only:
                continue
            picks = cache.outputs(voc.ik, (arm, move.obj, p, g), 1, resting)
            if not picks:
                continue
            for t in targets:
                place = self._place(arm, move.obj, t, g, picks[0][0], after)
                if place is not None:
                    found.append(Option(g, picks[0][0], t, place))
                    break
            if len(found) >= limit:
                break
        return found

    def _place(
        self, arm: str, obj: str, target: str, g: str, pick: str, after: tuple[Atom, ...]
    ) -> str | None:
        """The configuration placing ``obj`` at ``target`` with ``g`` that ``arm`` reaches
        soonest from ``pick``, counting the expected extra time of the arm's next motion from
        it (the domain's one-arm estimates; the IK stream's first when the domain has none,
        or when ``place_branches`` is 1; the first of equals). The IK stream may offer the
        same hold turned by a half turn of the wrist (a symmetric object): the transfer then
        turns the wrist the shorter way, or the way that keeps it clear of its limits."""
        cache = self.cache
        limit = self.options.place_branches if cache.voc.arm_distance in cache.functions else 1
        places = [q for (q,) in cache.outputs(cache.voc.ik, (arm, obj, target, g), limit, after)]
        if not places:
            return None
        return min(places, key=lambda q: cache.arm_distance(pick, q) + cache.next_motion(q))

    def _combinations(
        self,
        step: Step,
        arms: tuple[str, ...],
        per_move: Sequence[Sequence[Option]],
        mode: MotionMode,
        misses: Counter[str] | None = None,
        stage: Hashable = None,
    ) -> list[Grounding]:
        """The groundings of every combination of the moves' options not yet tried whose
        dual-arm configurations are collision-free; ``misses`` counts why the others fail
        (``stage``: how many options of how many grasps, for :meth:`_pair_table`)."""
        idle = [a for a in self.home if a not in arms]
        current = self.cache.current_dualconf()
        found: list[Grounding] = []
        misses = Counter() if misses is None else misses
        table = self.k.pair_table(step, arms, per_move, misses, stage)
        if isinstance(table, str):
            return found
        for chosen in itertools.product(*(range(len(o)) for o in per_move)):
            combo = tuple(o[k] for o, k in zip(per_move, chosen, strict=True))
            if self.tabu.blocked(self.key(step, arms, combo), mode):
                misses[_TRIED] += 1
                self._tabu_met = True
                continue
            why = table.why_not(chosen) if table is not None else None
            if why is not None:
                misses[why] += 1
                continue
            if not self.options.one_arm_at_a_time and not self._grippers_clear(step, combo):
                misses[_GRIPPERS] += 1
                continue
            if self.options.one_arm_at_a_time:
                one = self._ground_one_arm(step, arms, combo, current)
                if one is not None:
                    found.append(one)
                else:
                    misses[_ONE_ARM] += 1
                continue
            pick = {a: o.pick for a, o in zip(arms, combo, strict=True)}
            place = {a: o.place for a, o in zip(arms, combo, strict=True)}
            for a in idle:  # the idle arm waits at its retract (home) configuration
                pick[a] = place[a] = self.home[a]
            d_pick = self._combine(pick)
            if d_pick is None:
                misses[_AT_PICK] += 1
                continue
            d_place = self._combine(place)
            if d_place is None:
                misses[_AT_PLACE] += 1
                continue
            distance = self.cache.distance
            estimate = distance(current, d_pick) + distance(d_pick, d_place)
            found.append(Grounding(step, arms, combo, d_pick, d_place, estimate))
        return found

    def _grippers_clear(self, step: Step, combo: tuple[Option, ...]) -> bool:
        """Objects placed at once: each gripper is clear of every other object at its target
        (the domain's gripper test, when it has one; the IK of a placement sees only the
        objects that stay)."""
        test = self.cache.voc.grasp_cfree
        if len(combo) < 2 or test not in self.cache.streams:
            return True
        placed = list(zip(step.objects, combo, strict=True))
        return all(
            self.cache.test(test, (a, oa.target, oa.grasp, b, ob.target))
            and self.cache.test(test, (b, ob.target, ob.grasp, a, oa.target))
            for (a, oa), (b, ob) in itertools.combinations(placed, 2)
        )

    def _combine(self, confs: Mapping[str, str]) -> str | None:
        """The cell configuration of ``confs`` (arm -> configuration), the arms not in it at
        home, through the domain's combine stream (one pair per arm, in arm order)."""
        every = {**self.home, **confs}
        inputs = tuple(x for arm, q in sorted(every.items()) for x in (arm, q))
        out = self.cache.outputs(self.cache.voc.combine, inputs, 1)
        return out[0][0] if out else None

    def _ground_one_arm(
        self, step: Step, arms: tuple[str, ...], combo: tuple[Option, ...], current: str
    ) -> Grounding | None:
        """The baseline motion planner's grounding: every gripper action happens with the
        acting arm at its configuration and the other arm at home (its retract pose)."""
        sequence: list[Event] = []
        for index, pick in one_arm_order(self.cache, step, [o.target for o in combo]):
            arm = arms[index]
            option = combo[index]
            confs = dict(self.home)
            confs[arm] = option.pick if pick else option.place
            d = self._combine(confs)
            if d is None:
                return None
            sequence.append(Event(index, pick, d))
        estimate, d0 = 0.0, current
        for event in sequence:
            estimate += self.cache.distance(d0, event.conf)
            d0 = event.conf
        first, last = sequence[0].conf, sequence[-1].conf
        return Grounding(step, arms, combo, first, last, estimate, tuple(sequence))


def grounding_stages(step: Step, opt: SdarOptions, pairwise: bool) -> list[tuple[int, int]]:
    """``(options per move, grasps)`` per stage of :meth:`Grounder._ground` (more than two
    moves: see the module docstring on :data:`MAX_COMBINATIONS`)."""
    first, more = opt.options_per_move, opt.more_options
    size = len(step.moves)
    if size > 2:
        cut = max(1, int(MAX_COMBINATIONS ** (1.0 / (2 if pairwise else size)) + 1e-9))
        first, more = min(first, cut), min(more, cut)
    stages = [(first, opt.grasps)]
    if step.kind in opt.expand_kinds and more > first:
        stages.append((more, opt.grasps))
    if step.kind in opt.pair_kinds and opt.pair_grasps > opt.grasps and size <= 2:
        stages.append((opt.pair_grasps, opt.pair_grasps))
    return stages


#: The most combinations of options per stage grounded for a step of more than two moves (the
#: two-arm expanded stage's 6 x 6).
MAX_COMBINATIONS = 36
_NO_FREE_PAIR = "no pair of grasps keeps the arms apart, whatever the other objects"
_TRIED = "tried before"
_GRIPPERS = "a gripper meets the other object at its target"
_ONE_ARM = "an arm collides with the other arm at home"
_AT_PICK = AT_PICK
_AT_PLACE = AT_PLACE


def _no_grounding(misses: Counter[str]) -> str:
    """Why no combination of the moves' options was a grounding, by count."""
    if not misses:
        return "no combination of grasp options to try"
    parts = ", ".join(f"{why} ({n})" for why, n in misses.most_common())
    return f"no combination of grasp options works: {parts}"
