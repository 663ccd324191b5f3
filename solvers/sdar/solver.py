"""SDAR-M: best-first grounding of task-planner candidates through a domain's streams.

The solver executes rather than searches. From the current state it asks the task planner
(:mod:`solvers.sdar.sdar_t` or :mod:`solvers.sdar.baseline`) for ranked candidate steps, built
from the dependency graph that the domain's overlap test stream induces; it grounds the best
candidates through the streams (grasps, IK at the current pose and at the target with the same
grasp, buffers, dual-arm configurations) for both arm assignments, ranks the groundings by the
task planner's rank and then by the estimated motion time (the domain's distance function),
plans the two synchronous motions of the chosen one (to the objects, then to the targets; the
motion stream carries the fallback ladder of trajectory optimisation, arm untangling and one
arm at a time) and applies the domain's actions. When a candidate cannot be grounded or its
motion fails, the next one is tried; single-arm candidates come last. The run ends when the
goal holds, when no candidate works (``infeasible``, with the reasons) or at ``max_time``.

Every applied action is checked against the domain's lifted precondition
(:class:`solvers.sdar.state.LiftedState`), so the plan is a plan of ``domain.pddl``.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from sdar_tamp.errors import ParameterError
from sdar_tamp.graph import DependencyGraph
from sdar_tamp.language.model import And, Atom, FunctionTerm
from sdar_tamp.language.options import FunctionInfo, StreamInfo
from sdar_tamp.language.problem import PDDLProblem, type_facts
from solvers.sdar.state import LiftedState
from solvers.sdar.tasks import Move, Step, TaskPlanner, TaskView
from solvers.sdar.vocabulary import SdarVocabulary
from solvers.solution import Action, Certificate, Solution, Status, StreamStatistics
from solvers.stream_planning.engine import bind_externals
from solvers.stream_planning.externals import StreamExternal, StreamInstance

LOG = logging.getLogger(f"sdar_tamp.{__name__}")  # under the package prefix (sdar_tamp.logs)


@dataclass(frozen=True)
class SdarOptions:
    """Budgets of SDAR-M (see the module docstring)."""

    max_time: float = math.inf  # [s]
    candidates: int = 8  # candidate steps grounded per decision (more if none works)
    choose_among: int = 3  # feasible groundings compared by estimated motion time
    grasps: int = 6  # grasps tried per object
    options_per_move: int = 2  # (grasp, pick IK, place IK) options kept per arm and move
    more_options: int = 6  # kept instead when every pair of the first ones makes the arms collide
    expand_kinds: tuple[str, ...] = ("pair", "swap", "chain", "cycle")  # two-move steps
    buffers: int = 4  # buffer poses tried per buffer move
    one_arm_at_a_time: bool = False  # the baseline motion planner (see _execute_one_arm)
    quick_attempts: int = 6  # best-ranked groundings tried with the quick motion stream first
    progress: Callable[[int, int], None] | None = None  # (objects at goal, objects) per step
    vocabulary: SdarVocabulary = field(default_factory=SdarVocabulary)


@dataclass(frozen=True)
class _Option:
    grasp: str
    pick: str  # arm configuration at the current pose
    target: str  # pose
    place: str  # arm configuration at the target


@dataclass(frozen=True)
class _Event:
    """One gripper action of a one-arm-at-a-time execution, at ``conf``: the acting arm at
    its pick or place configuration, the other arm at home."""

    index: int  # into the step's moves
    pick: bool
    conf: str  # dual-arm configuration


@dataclass(frozen=True)
class _Grounding:
    """A step with arms and options; ``d_pick`` / ``d_place``: the dual-arm configurations of
    the first and of the last gripper action."""

    step: Step
    arms: tuple[str, ...]
    options: tuple[_Option, ...]
    d_pick: str
    d_place: str
    estimate: float
    sequence: tuple[_Event, ...] = ()  # one arm at a time only


@dataclass
class _TaskRecord:
    kind: str
    objects: tuple[str, ...]
    arms: tuple[str, ...]
    to_buffer: tuple[bool, ...]
    selection_time: float = 0.0
    motion_time: float = 0.0
    motions: int = 0
    tried: int = 0
    motion_times: list[float] = field(default_factory=list)  # [s] per motion planned


class SdarSolver:
    """One solve of a rearrangement problem (see the module docstring)."""

    def __init__(
        self,
        problem: PDDLProblem,
        planner: TaskPlanner,
        options: SdarOptions | None = None,
        stream_info: Mapping[str, StreamInfo | FunctionInfo] | None = None,
    ) -> None:
        self.problem = problem
        self.planner = planner
        self.options = options or SdarOptions()
        self.voc = self.options.vocabulary
        self.table = problem.objects.copy()
        self.streams, self.functions = bind_externals(problem, stream_info)
        self.voc.check(problem.domain, self.streams, self.functions)
        self.types: dict[str, set[str]] = {}
        hierarchy = problem.domain.types
        for name, type_name in problem.facts.objects.items():
            for ancestor in hierarchy.ancestors(type_name):
                self.types.setdefault(ancestor, set()).add(name)
        self.numeric = dict(problem.facts.numeric)
        init = set(problem.facts.init) | type_facts(problem.facts.objects, hierarchy)
        self.state = LiftedState(problem.domain, (), init, self._of_type, self._cost)
        self.goals = self._goal_poses(problem)
        self.instances: dict[tuple[str, tuple[str, ...], tuple[Atom, ...]], StreamInstance] = {}
        self.plan: list[tuple[str, tuple[str, ...]]] = []
        self.cost = 0.0
        self.records: list[_TaskRecord] = []
        self.tabu: set[tuple[Any, ...]] = set()
        self.quick_tabu: set[tuple[Any, ...]] = set()  # failed with the quick motion stream
        self._quick = False  # motions come from the quick motion stream
        self._decision = (0.0, 0.0)  # (start [s], motion_time then) of the current decision
        self.failures: list[str] = []  # why candidates of the current decision failed
        self.evictions = 0
        self.deadline = math.inf
        self.deferred: dict[str, str] = {}  # evicted object -> the object it blocked
        self.motion_time = 0.0
        self.home = {arm: self._home_conf(arm) for arm in sorted(self._of_type(self.voc.arm_type))}

    # -- set-up ------------------------------------------------------------------------------
    def _goal_poses(self, problem: PDDLProblem) -> dict[str, str]:
        goal = problem.facts.goal
        parts = goal.parts if isinstance(goal, And) else (goal,)
        goals: dict[str, str] = {}
        for part in parts:
            if not isinstance(part, Atom) or part.predicate != self.voc.atpose:
                raise ParameterError(
                    f"algorithm 'sdar' needs a goal that is a conjunction of "
                    f"({self.voc.atpose} ?object ?pose) facts; got {part}"
                )
            goals[part.args[0]] = part.args[1]
        return goals

    def _home_conf(self, arm: str) -> str:
        current = self._current_dualconf()
        for d, a, q in self.state.atoms(self.voc.confin):
            if d == current and a == arm:
                return q
        raise ParameterError(
            f"algorithm 'sdar' needs the initial ({self.voc.confin} ?d ?arm ?q) facts of the "
            f"initial ({self.voc.atdualconf} ?d); none for arm {arm!r}"
        )

    def _of_type(self, type_name: str) -> Sequence[str]:
        return sorted(self.types.get(type_name, ()))

    def _cost(self, term: FunctionTerm) -> float:
        key = (term.name, tuple(term.args))
        if key not in self.numeric:
            external = self.functions.get(term.name)
            if external is None:
                raise ParameterError(f"no value for the cost term {key}")
            self.numeric[key] = float(external.evaluate(key[1], self.table))
        return self.numeric[key]

    # -- streams -----------------------------------------------------------------------------
    def _outputs(
        self, stream: str, inputs: tuple[str, ...], limit: int, fluents: tuple[Atom, ...] = ()
    ) -> list[tuple[str, ...]]:
        external: StreamExternal = self.streams[stream]
        if not external.declaration.fluents:
            fluents = ()
        key = (stream, inputs, fluents)
        instance = self.instances.get(key)
        if instance is None:
            instance = self.instances[key] = StreamInstance(external, inputs, fluents)
        while len(instance.results) < limit and not instance.exhausted:
            results, wild = instance.next(self.table)
            for result in results:
                self._certify(result.certified)
            self._certify(wild)
        return [r.outputs for r in instance.results[:limit]]

    def _certify(self, atoms: Sequence[Atom]) -> None:
        for atom in atoms:
            if len(atom.args) == 1 and atom.predicate in self.problem.domain.types.parents:
                for ancestor in self.problem.domain.types.ancestors(atom.predicate):
                    self.types.setdefault(ancestor, set()).add(atom.args[0])
        self.state.add_static(atoms)

    def _test(self, stream: str, inputs: tuple[str, ...]) -> bool:
        return bool(self._outputs(stream, inputs, 1))

    def _fluents(self, *predicates: str, without: frozenset[str] = frozenset()) -> tuple[Atom, ...]:
        out = [
            Atom(p, args)
            for p in predicates
            for args in self.state.atoms(p)
            if not (p == self.voc.atpose and args[0] in without)
        ]
        return tuple(sorted(out, key=str))

    # -- the current arrangement -------------------------------------------------------------
    def _current_dualconf(self) -> str:
        (d,) = next(self.state.atoms(self.voc.atdualconf))
        return d

    def _current_poses(self) -> dict[str, str]:
        return {o: p for o, p in self.state.atoms(self.voc.atpose)}

    def view(self) -> TaskView:
        """The dependency graph of the objects not at their goals (overlap test stream)."""
        current = self._current_poses()
        remaining = tuple(sorted(o for o, g in self.goals.items() if current.get(o) != g))
        edges = []
        for i, a in enumerate(remaining):
            for j, b in enumerate(remaining):
                if (
                    i != j
                    and b in current
                    and self._test(self.voc.overlap, (a, self.goals[a], b, current[b]))
                ):
                    edges.append((i, j))
        buffered = frozenset(
            o for o, p in current.items() if self.state.has(self.voc.buffer_pose, p)
        )
        done = frozenset(o for o, g in self.goals.items() if current.get(o) == g)
        return TaskView(DependencyGraph(remaining, tuple(edges)), done, buffered)

    # -- grounding ---------------------------------------------------------------------------
    def _move_options(
        self, arm: str, move: Move, lifted: frozenset[str], limit: int
    ) -> list[_Option]:
        voc, opt = self.voc, self.options
        current = self._current_poses()
        p = current[move.obj]
        resting = self._fluents(voc.atpose)
        if move.to_buffer:
            targets = [out[0] for out in self._outputs(voc.buffer, (move.obj,), opt.buffers,
                                                         resting)]  # fmt: skip
        else:
            targets = [self.goals[move.obj]]
        after = self._fluents(voc.atpose, without=lifted)
        found: list[_Option] = []
        for (g,) in self._outputs(voc.grasp, (move.obj,), opt.grasps):
            picks = self._outputs(voc.ik, (arm, move.obj, p, g), 1, resting)
            if not picks:
                continue
            for t in targets:
                places = self._outputs(voc.ik, (arm, move.obj, t, g), 1, after)
                if places:
                    found.append(_Option(g, picks[0][0], t, places[0][0]))
                    break
            if len(found) >= limit:
                break
        return found

    def _combine(self, confs: Mapping[str, str]) -> str | None:
        (a1, q1), (a2, q2) = sorted(confs.items())
        out = self._outputs(self.voc.combine, (a1, q1, a2, q2), 1)
        return out[0][0] if out else None

    def _distance(self, d1: str, d2: str) -> float:
        if self.voc.distance not in self.functions or d1 == d2:
            return 0.0
        return float(self.functions[self.voc.distance].evaluate((d1, d2), self.table))

    def _ground(self, step: Step, arms: tuple[str, ...]) -> list[_Grounding]:
        """Every grounding of ``step`` with ``arms`` not yet tried, cheapest estimate first:
        from ``options_per_move`` options per move, or from ``more_options`` when none of
        those combinations works (two arms reaching for neighbouring objects often collide
        with the first grasps and not with tilted ones)."""
        lifted = frozenset(step.objects)
        opt = self.options
        limits = [opt.options_per_move]
        if step.kind in opt.expand_kinds and opt.more_options > opt.options_per_move:
            limits.append(opt.more_options)
        for limit in limits:
            per_move = [
                self._move_options(a, m, lifted, limit)
                for a, m in zip(arms, step.moves, strict=True)
            ]
            for a, m, options in zip(arms, step.moves, per_move, strict=True):
                if not options:
                    target = "a buffer" if m.to_buffer else "its goal"
                    self._why(step, arms, f"no grasp with IK for {self._show(a)} at "
                              f"{self._show(m.obj)} and at {target}")  # fmt: skip
                    return []
            found = self._combinations(step, arms, per_move)
            if found or all(len(options) < limit for options in per_move):
                break
        if not found:
            self._why(step, arms, "the arms' configurations collide (or were tried)")
        return sorted(found, key=lambda g: g.estimate)

    def _combinations(
        self, step: Step, arms: tuple[str, ...], per_move: Sequence[Sequence[_Option]]
    ) -> list[_Grounding]:
        """The groundings of every combination of the moves' options not yet tried whose
        dual-arm configurations are collision-free."""
        idle = [a for a in self.home if a not in arms]
        current = self._current_dualconf()
        found: list[_Grounding] = []
        for combo in _product(per_move):
            key = self._tabu_key(step, arms, combo)
            if key in self.tabu or (self._quick and key in self.quick_tabu):
                continue
            if self.options.one_arm_at_a_time:
                one = self._ground_one_arm(step, arms, combo, current)
                if one is not None:
                    found.append(one)
                continue
            pick = {a: o.pick for a, o in zip(arms, combo, strict=True)}
            place = {a: o.place for a, o in zip(arms, combo, strict=True)}
            for a in idle:  # the idle arm waits at its retract (home) configuration
                pick[a] = place[a] = self.home[a]
            d_pick, d_place = self._combine(pick), self._combine(place)
            if d_pick is None or d_place is None:
                continue
            estimate = self._distance(current, d_pick) + self._distance(d_pick, d_place)
            found.append(_Grounding(step, arms, combo, d_pick, d_place, estimate))
        return found

    def _ground_one_arm(
        self, step: Step, arms: tuple[str, ...], combo: tuple[_Option, ...], current: str
    ) -> _Grounding | None:
        """The baseline motion planner's grounding: every gripper action happens with the
        acting arm at its configuration and the other arm at home (its retract pose)."""
        sequence: list[_Event] = []
        for index, pick in self._one_arm_order(step, [o.target for o in combo]):
            arm = arms[index]
            option = combo[index]
            confs = {a: self.home[a] for a in self.home}
            confs[arm] = option.pick if pick else option.place
            d = self._combine(confs)
            if d is None:
                return None
            sequence.append(_Event(index, pick, d))
        estimate, d0 = 0.0, current
        for event in sequence:
            estimate += self._distance(d0, event.conf)
            d0 = event.conf
        first, last = sequence[0].conf, sequence[-1].conf
        return _Grounding(step, arms, combo, first, last, estimate, tuple(sequence))

    def _one_arm_order(self, step: Step, targets: Sequence[str]) -> list[tuple[int, bool]]:
        """``(move index, pick?)`` in execution order. A move whose target is clear of every
        other resting object goes first, alone, then the other; otherwise (a swap) the first
        arm picks and waits at home holding its object while the second arm works."""
        if len(step.moves) == 1:
            return [(0, True), (0, False)]
        current = self._current_poses()
        for k, (obj, target) in enumerate(zip(step.objects, targets, strict=True)):
            if all(
                self._test(self.voc.cfree, (obj, target, other, pose))
                for other, pose in current.items()
                if other != obj
            ):
                return [(k, True), (k, False), (1 - k, True), (1 - k, False)]
        return [(0, True), (1, True), (1, False), (0, False)]

    def _tabu_key(self, step: Step, arms: tuple[str, ...], combo: tuple[_Option, ...]) -> Any:
        return (self._fluents(self.voc.atpose), step.moves, arms, combo)

    def _show(self, name: str) -> str:
        return str(self.table.value(name))

    def _why(self, step: Step, arms: tuple[str, ...], reason: str) -> None:
        what = ", ".join(
            f"{self._show(m.obj)}{'->buffer' if m.to_buffer else ''} by {self._show(a)}"
            for m, a in zip(step.moves, arms, strict=True)
        )
        self.failures.append(f"{step.kind} ({what}): {reason}")
        LOG.debug("sdar: %s (%s): %s", step.kind, what, reason)

    def _assignments(self, step: Step) -> list[tuple[str, ...]]:
        arms = sorted(self.home)
        if len(step.moves) == 1:
            return [(a,) for a in arms]
        return [(arms[0], arms[1]), (arms[1], arms[0])]

    def _select(self, candidates: Sequence[Step]) -> list[_Grounding]:
        """Feasible groundings, best first: task-planner rank, then estimated motion time."""
        found: list[_Grounding] = []
        for index, step in enumerate(candidates):
            if time.perf_counter() > self.deadline:
                break
            if found and (
                step.rank > found[0].step.rank
                or (index >= self.options.candidates and len(found) >= 1)
                or len(found) >= self.options.choose_among
            ):
                break
            for arms in self._assignments(step):
                found.extend(self._ground(step, arms))
            found.sort(key=lambda g: (g.step.rank, g.estimate))
        return found

    # -- execution ---------------------------------------------------------------------------
    def _motion(
        self, d1: str, d2: str, record: _TaskRecord, fluents: tuple[Atom, ...]
    ) -> str | None:
        start = time.perf_counter()
        stream = self.voc.quick_motion if self._quick else self.voc.motion
        out = self._outputs(stream, (d1, d2), 1, fluents)
        elapsed = time.perf_counter() - start
        self.motion_time += elapsed
        if out:
            record.motion_times.append(elapsed)
        return out[0][0] if out else None

    def _apply(self, name: str, *args: str) -> None:
        self.cost += self.state.apply(name, args)
        self.plan.append((name, args))

    def _gripper(self, which: str, g: _Grounding, poses: Sequence[str], confs: Sequence[str],
                 d: str) -> None:  # fmt: skip
        parts = [
            (arm, move.obj, pose, option.grasp, conf)
            for arm, move, option, pose, conf in zip(
                g.arms, g.step.moves, g.options, poses, confs, strict=True
            )
        ]
        single = self.voc.pick if which == "pick" else self.voc.place
        both = self.voc.pick_both if which == "pick" else self.voc.place_both
        if len(parts) == 1:
            arm, obj, pose, grasp, conf = parts[0]
            self._apply(single, arm, obj, pose, grasp, conf, d)
        else:
            self._apply(both, d, *parts[0], *parts[1])

    def _certify_placements(self, g: _Grounding, targets: Sequence[str]) -> None:
        resting = self._current_poses()
        placed = list(zip(g.step.objects, targets, strict=True))
        for obj, target in placed:
            for other, pose in resting.items():
                self._test(self.voc.cfree, (obj, target, other, pose))
        if len(placed) == 2:
            self._test(self.voc.cfree, (*placed[0], *placed[1]))

    def _execute(self, g: _Grounding, record: _TaskRecord) -> bool:
        """Plan the transfer (in the state after the pick), then the approach; apply both
        only when both exist, so a failed candidate leaves nothing in the plan."""
        voc = self.voc
        start_poses = [self._current_poses()[o] for o in g.step.objects]
        targets = [o.target for o in g.options]
        self._certify_placements(g, targets)
        if not self._placeable(g, targets):
            self._why(g.step, g.arms, "a target is not clear of the resting objects")
            return False
        if g.sequence:
            return self._execute_one_arm(g, record)
        held = [
            Atom(voc.holding, (arm, move.obj, option.grasp))
            for arm, move, option in zip(g.arms, g.step.moves, g.options, strict=True)
        ]
        lifted = frozenset(g.step.objects)
        after_pick = tuple(sorted((*self._fluents(voc.atpose, without=lifted), *held), key=str))
        t2 = self._motion(g.d_pick, g.d_place, record, after_pick)
        if t2 is None:
            self._why(g.step, g.arms, "no motion to the targets")
            return False
        d0 = self._current_dualconf()
        t1 = None
        if d0 != g.d_pick:
            t1 = self._motion(d0, g.d_pick, record, self._fluents(voc.atpose, voc.holding))
            if t1 is None:
                self._why(g.step, g.arms, "no motion to the objects")
                return False
            self._apply(voc.move, d0, t1, g.d_pick)
            record.motions += 1
        self._gripper("pick", g, start_poses, [o.pick for o in g.options], g.d_pick)
        self._apply(voc.move, g.d_pick, t2, g.d_place)
        record.motions += 1
        self._gripper("place", g, targets, [o.place for o in g.options], g.d_place)
        return True

    def _execute_one_arm(self, g: _Grounding, record: _TaskRecord) -> bool:
        """Execute ``g.sequence``: before each gripper action one motion brings the acting arm
        to its configuration and the other home, one arm at a time (the motion stream's
        planner moves them in turn). Every motion is planned, in the state it starts from,
        before any action is applied."""
        voc = self.voc
        poses = self._current_poses()
        held: dict[str, tuple[str, str]] = {}  # arm -> (object, grasp)
        d = self._current_dualconf()
        actions: list[tuple[str, tuple[str, ...]]] = []
        for event in g.sequence:
            k = event.index
            arm, move, option = g.arms[k], g.step.moves[k], g.options[k]
            if d != event.conf:
                fluents = tuple(sorted(
                    [Atom(voc.atpose, (o, p)) for o, p in poses.items()]
                    + [Atom(voc.holding, (a, o, grasp)) for a, (o, grasp) in held.items()],
                    key=str,
                ))  # fmt: skip
                t = self._motion(d, event.conf, record, fluents)
                if t is None:
                    self._why(g.step, g.arms, f"no one-arm motion for {self._show(arm)}")
                    return False
                actions.append((voc.move, (d, t, event.conf)))
                d = event.conf
            if event.pick:
                pose = poses.pop(move.obj)
                held[arm] = (move.obj, option.grasp)
                actions.append((voc.pick, (arm, move.obj, pose, option.grasp, option.pick, d)))
            else:
                for other, pose in poses.items():  # certify what the placement needs
                    self._test(voc.cfree, (move.obj, option.target, other, pose))
                poses[move.obj] = option.target
                del held[arm]
                actions.append(
                    (voc.place, (arm, move.obj, option.target, option.grasp, option.place, d))
                )
        for name, args in actions:
            self._apply(name, *args)
            if name == voc.move:
                record.motions += 1
        return True

    def _placeable(self, g: _Grounding, targets: Sequence[str]) -> bool:
        """Every target is certified clear of the objects resting after the pick (and of the
        other target)."""
        lifted = set(g.step.objects)
        resting = {o: p for o, p in self._current_poses().items() if o not in lifted}
        placed = list(zip(g.step.objects, targets, strict=True))
        cfree = self.streams[self.voc.cfree].declaration.certified[0].predicate
        clear = all(
            self.state.has(cfree, obj, t, other, p)
            for obj, t in placed
            for other, p in resting.items()
        )
        if len(placed) == 2:
            clear = clear and self.state.has(cfree, *placed[0], *placed[1])
        return clear

    # -- the loop ----------------------------------------------------------------------------
    def solve(self) -> Solution:
        start = time.perf_counter()
        self.deadline = start + self.options.max_time
        status = Status.SOLVED
        diagnosis: list[str] = []
        while True:
            # a decision's time, failed attempts included, is booked on the task it executes
            self._decision = (time.perf_counter(), self.motion_time)
            view = self.view()
            if not view.remaining:
                break
            if time.perf_counter() - start > self.options.max_time:
                status = Status.TIMEOUT
                diagnosis.append(f"max_time reached with {len(view.remaining)} object(s) left")
                break
            if self.options.progress is not None:
                self.options.progress(len(view.done), len(self.goals))
            candidates = self._allowed(self.planner.candidates(view))
            self.failures = []
            if self._decide(view, candidates):
                continue
            if time.perf_counter() > self.deadline:
                status = Status.TIMEOUT
                diagnosis.append(f"max_time reached with {len(view.remaining)} object(s) left")
                break
            status = Status.INFEASIBLE
            left = ", ".join(self._show(o) for o in view.remaining)
            diagnosis.append(
                f"no candidate step could be grounded and executed; "
                f"{len(view.remaining)} object(s) left ({left})"
            )
            diagnosis.extend(dict.fromkeys(self.failures))
            break
        if self.options.progress is not None:
            self.options.progress(len(self.goals) - len(self.view().remaining), len(self.goals))
        return self._solution(status, diagnosis, time.perf_counter() - start)

    def _decide(self, view: TaskView, candidates: Sequence[Step]) -> bool:
        """Execute one step: a candidate that brings an object to its goal if any works;
        otherwise an eviction (dead-end recovery); otherwise a candidate that only buffers."""
        productive = [s for s in candidates if s.progress > 0]
        if self._step(view, productive):
            return True
        if self.evictions < 2 * len(self.goals):
            evictions = self._evictions(view)
            if evictions and self._step(view, evictions, commit=False):
                self.evictions += 1
                return True
        return self._step(view, [s for s in candidates if s.progress == 0])

    def _evictions(self, view: TaskView) -> list[Step]:
        """Dead-end recovery: objects at their goals whose absence would let a remaining object
        be grasped where it rests or at its goal (found by asking the IK stream without them),
        moved to a buffer, together with the object they unblock when possible."""
        steps: list[Step] = []
        current = self._current_poses()
        for obj in view.remaining:
            if not self._reachable(obj, current[obj], frozenset()):
                pose, unblocks_goal = current[obj], False  # crowded where it rests
            elif not view.blockers(obj) and not self._reachable(
                obj, self.goals[obj], frozenset((obj,))
            ):
                pose, unblocks_goal = self.goals[obj], True  # crowded at its goal
            else:
                continue
            lifted = frozenset((obj,)) if unblocks_goal else frozenset()
            done = sorted(view.done)
            singles = [o for o in done if self._reachable(obj, pose, lifted | {o})]
            for other in singles:
                self.deferred[other] = obj
                if unblocks_goal:
                    steps.append(Step((Move(obj), Move(other, True)), "evict", 0))
                steps.append(Step((Move(other, True),), "evict", 1))
            if singles:
                continue
            for i, a in enumerate(done):  # boxed in from two sides: two objects make room
                if time.perf_counter() > self.deadline:
                    return steps
                for b in done[i + 1 :]:
                    if self._reachable(obj, pose, lifted | {a, b}):
                        self.deferred[a] = self.deferred[b] = obj
                        steps.append(Step((Move(a, True), Move(b, True)), "evict", 2))
        return steps

    def _reachable(self, obj: str, pose: str, lifted: frozenset[str]) -> bool:
        """Some arm grasps ``obj`` at ``pose`` with some grasp while ``lifted`` are away."""
        voc = self.voc
        fluents = self._fluents(voc.atpose, without=lifted)
        return any(
            self._outputs(voc.ik, (arm, obj, pose, g), 1, fluents)
            for arm in self.home
            for (g,) in self._outputs(voc.grasp, (obj,), self.options.grasps)
        )

    def _allowed(self, candidates: Sequence[Step]) -> list[Step]:
        """Candidates that do not bring an evicted object back before the one it blocked."""
        done = {o for o, g in self.goals.items() if self._current_poses().get(o) == g}
        for other, obj in list(self.deferred.items()):
            if obj in done:
                del self.deferred[other]
        return [
            s
            for s in candidates
            if not any(not m.to_buffer and m.obj in self.deferred for m in s.moves)
        ] or list(candidates)

    def _step(self, view: TaskView, candidates: Sequence[Step], commit: bool = True) -> bool:
        """Execute the best grounding whose motions exist. With a quick motion stream, up to
        ``quick_attempts`` groundings of the best rank are tried with it first (a cheap
        motion for another grounding beats the fallbacks of the motion planner for the
        first one); then every grounding with the full motion planner."""
        try:
            return self._try_groundings(view, candidates, commit)
        finally:
            self._quick = False

    def _try_groundings(self, view: TaskView, candidates: Sequence[Step], commit: bool) -> bool:
        task_start, motion_before = self._decision
        tried = 0
        quick_left = self.options.quick_attempts if self.voc.quick_motion in self.streams else 0
        best_rank: int | None = None
        while time.perf_counter() <= self.deadline:
            self._quick = quick_left > 0
            groundings = self._select(candidates)
            if self._quick:
                if best_rank is None and groundings:
                    best_rank = groundings[0].step.rank
                if not groundings or groundings[0].step.rank != best_rank:
                    quick_left = 0  # the best rank is used up: the full motion planner
                    continue
            if not groundings:
                return False
            g = groundings[0]
            tried += 1
            record = _TaskRecord(
                g.step.kind, g.step.objects, g.arms, tuple(m.to_buffer for m in g.step.moves)
            )
            key = self._tabu_key(g.step, g.arms, g.options)
            ok = self._execute(g, record)
            record.tried = tried
            record.motion_time = self.motion_time - motion_before
            record.selection_time = time.perf_counter() - task_start - record.motion_time
            if ok:
                self.records.append(record)
                if commit:
                    self.planner.commit(g.step, view)
                return True
            if self._quick:
                self.quick_tabu.add(key)
                quick_left -= 1
            else:
                self.tabu.add(key)
        return False

    def _solution(self, status: Status, diagnosis: list[str], elapsed: float) -> Solution:
        value = self.table.value
        plan = [Action(name, tuple(value(a) for a in args)) for name, args in self.plan]
        facts = tuple(
            (p, *(value(a) for a in args))
            for p in sorted(self.state._by_predicate)
            if p not in self.state.fluent_names
            for args in self.state.atoms(p)
        )
        motions = sum(r.motions for r in self.records)
        selection = sum(r.selection_time for r in self.records)
        statistics = {
            "planning_time": elapsed,
            "selection_time": elapsed - self.motion_time,
            "motion_time": self.motion_time,
            "tasks": float(len(self.records)),
            "steps": float(motions),
            "task_selection_time": selection,
        }
        streams = {
            name: StreamStatistics(c.calls, c.successes, c.outputs, c.time)
            for name, c in (
                *((n, e.counters) for n, e in self.streams.items()),
                *((n, f.counters) for n, f in self.functions.items()),
            )
        }
        trace = tuple(
            {
                "kind": r.kind,
                "objects": tuple(value(o) for o in r.objects),
                "arms": tuple(value(a) for a in r.arms),
                "to_buffer": r.to_buffer,
                "selection_time": r.selection_time,
                "motion_time": r.motion_time,
                "motions": r.motions,
                "tried": r.tried,
                "motion_times": tuple(r.motion_times),
            }
            for r in self.records
        )
        solved = status is Status.SOLVED
        return Solution(
            plan if solved else None,
            self.cost if solved else math.inf,
            Certificate(facts, facts),
            status,
            statistics,
            streams,
            tuple(diagnosis),
            trace=trace,
            partial_plan=tuple(plan),
        )


def _product(options: Sequence[Sequence[_Option]]) -> list[tuple[_Option, ...]]:
    combos: list[tuple[_Option, ...]] = [()]
    for choices in options:
        combos = [(*c, o) for c in combos for o in choices]
    return combos
