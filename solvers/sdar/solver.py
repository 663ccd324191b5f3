"""SDAR-M: best-first grounding of task-planner candidates through a domain's streams.

The solver executes rather than searches. From the current state it asks the task planner
(:mod:`solvers.sdar.sdar_t` or :mod:`solvers.sdar.baseline`) for ranked candidate steps, built
from the dependency graph that the domain's overlap test stream induces; it grounds the best
candidates through the streams (grasps, IK at the current pose and at the target with the same
grasp, buffers, cell configurations) for the assignments of arms to its moves (every one with
two arms, a bounded few with more: :mod:`~solvers.sdar.grounding`), ranks the groundings by the
task planner's rank and then by the estimated motion time (the domain's distance function),
plans the two synchronous motions of the chosen one (to the objects, then to the targets; the
motion stream carries the fallback ladder of trajectory optimisation, arm untangling and one
arm at a time) and applies the domain's actions. When a candidate cannot be grounded or its
motion fails, the next one is tried; single-arm candidates come last. The run ends when the
goal holds, when no candidate works (``infeasible``, with the reasons) or at ``max_time``.
:meth:`SdarSolver.steps` yields each executed decision (a
:class:`~solvers.sdar.report.PlannedStep`) as soon as it is executed, and
:meth:`SdarSolver.solve` runs it to its end: one loop for both.

Every applied action is checked against the domain's lifted precondition
(:class:`solvers.sdar.state.LiftedState`), so the plan is a plan of ``domain.pddl``.

The parts, around one :class:`~solvers.sdar.cache.StreamCache` (streams bound once, their
outputs and the lifted state): :mod:`~solvers.sdar.grounding` (options, dual-arm
configurations), :mod:`~solvers.sdar.execution` (motions and actions),
:mod:`~solvers.sdar.recovery` (evictions), :mod:`~solvers.sdar.viewing` (the task planner's
view of the state) and :mod:`~solvers.sdar.report` (records, the solution), with
:mod:`~solvers.sdar.attempts` (the motion mode of an attempt, the tabu lists and the
quick-stream ladder). This module holds the decision loop.
"""

from __future__ import annotations

import time
from collections.abc import Generator, Mapping, Sequence
from dataclasses import dataclass

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.formula_model import And, Atom
from sdar_tamp.language.options import FunctionInfo, StreamInfo
from sdar_tamp.language.problem import PDDLProblem
from sdar_tamp.logs import get_logger
from solvers.sdar.attempts import MotionMode, QuickLadder, TabuLists
from solvers.sdar.budget import Deadline
from solvers.sdar.cache import StreamCache
from solvers.sdar.execution import Executor
from solvers.sdar.grounding import Grounder
from solvers.sdar.options import SdarOptions
from solvers.sdar.recovery import Recovery
from solvers.sdar.report import (
    Failures,
    PlannedStep,
    RunSummary,
    TaskRecord,
    build_solution,
    planned_step,
)
from solvers.sdar.spending import (
    DecisionSpend,
    finish_pace,
    finishing_options,
    finishing_view,
    spread_steps,
)
from solvers.sdar.tasks import Step, TaskPlanner, TaskView
from solvers.sdar.viewing import current_view
from solvers.solution import Solution, Status

LOG = get_logger(__name__)

# SdarOptions and PlannedStep: their homes are options.py and report.py
__all__ = ["Decision", "PlannedStep", "SdarOptions", "SdarSolver", "run_to_end"]


@dataclass(frozen=True)
class Decision:
    """When the current decision started and the motion time spent before it: a decision's
    time, failed attempts included, is booked on the task it executes."""

    start: float  # [s] (time.perf_counter)
    motion_time: float  # [s]


def run_to_end(steps: Generator[PlannedStep, None, Solution]) -> Solution:
    """What a generator of :meth:`SdarSolver.steps` returns, after running it to its end."""
    while True:
        try:
            next(steps)
        except StopIteration as end:
            solution: Solution = end.value
            return solution


class SdarSolver:
    """One solve of a rearrangement problem (see the module docstring)."""

    def __init__(
        self,
        problem: PDDLProblem,
        planner: TaskPlanner,
        options: SdarOptions | None = None,
        stream_info: Mapping[str, StreamInfo | FunctionInfo] | None = None,
    ) -> None:
        self.planner = planner
        self.options = options or SdarOptions()
        self.voc = self.options.vocabulary
        self.cache = StreamCache(problem, self.voc, stream_info)
        self.goals = self._goal_poses(problem)
        arms = sorted(self.cache.of_type(self.voc.arm_type))
        self.home = {arm: self._home_conf(arm) for arm in arms}
        self.deadline = Deadline(self.options.max_time, self.options.clock)
        self.pace = finish_pace(self.options)
        """The run's measured pace, which sets the finish's reserve (None: no finish)."""
        self.failures = Failures(self.cache.show)
        self.tabu = TabuLists()
        self.grounder = Grounder(
            self.cache, self.options, self.goals, self.home, self.tabu, self.failures,
            self.deadline,
        )  # fmt: skip
        self.executor = Executor(self.cache, self.failures)
        self.recovery = Recovery(self.cache, self.options, self.goals, tuple(self.home),
                                 self.deadline)  # fmt: skip
        self.grounder.buffer_check = self.recovery.buffer_clear
        self.grounder.skip_family = self._family_spent
        self.records: list[TaskRecord] = []
        self.spend: DecisionSpend = DecisionSpend(len(self.home), self.options.fewer_moves_after)
        self.finishing = False
        """The anytime finish: small steps, the first grounding found
        (:mod:`~solvers.sdar.spending`)."""
        self._normal_grounding = (self.grounder.options, self.grounder.first_found)
        self.visited: set[frozenset[tuple[str, str]]] = set()  # arrangements met so far

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
        home = self.options.home
        current = self.cache.current_dualconf() if home is None else self.cache.table.name(home)
        for d, a, q in self.cache.state.atoms(self.voc.confin):
            if d == current and a == arm:
                return q
        raise ParameterError(
            f"algorithm 'sdar' needs the initial ({self.voc.confin} ?d ?arm ?q) facts of the "
            f"initial ({self.voc.atdualconf} ?d) or of SdarOptions.home; none for arm {arm!r}"
        )

    def view(self) -> TaskView:
        """The dependency graph of the objects not at their goals, with the layout when the
        cell has more than two arms (:func:`~solvers.sdar.viewing.current_view`)."""
        return current_view(self.cache, self.goals, tuple(self.home), self.options.plane)

    # -- the loop ----------------------------------------------------------------------------
    def solve(self) -> Solution:
        """Run :meth:`steps` to its end; its solution."""
        return run_to_end(self.steps())

    def steps(self) -> Generator[PlannedStep, None, Solution]:
        """The decision loop, one executed decision at a time: each is yielded as soon as its
        motions are planned and its actions applied (a :class:`PlannedStep`: the task and the
        plan actions it added); the generator returns the :class:`Solution` (the plan of every
        step yielded, in order). The clock of ``max_time`` runs from the first ``next``, the
        caller's time between steps included."""
        self.deadline.start()  # on the budget's clock (options.clock)
        start = time.perf_counter()  # the planning time: wall-clock seconds, whatever the budget's
        status = Status.SOLVED
        diagnosis: list[str] = []
        while True:
            decision = Decision(time.perf_counter(), self.executor.motion_time)
            view = self.view()
            if not view.remaining:
                break
            self._pace(len(view.remaining))
            clock = self.options.clock()
            self.grounder.layout = view.layout
            whole = view
            if self.finishing:
                view = finishing_view(view, self.options.finish_moves)
            if self.deadline.expired():
                status = Status.TIMEOUT
                diagnosis.append(f"max_time reached with {len(view.remaining)} object(s) left")
                break
            if self.options.progress is not None:
                self.options.progress(len(view.done), len(self.goals))
            self.visited.add(self._arrangement())
            proposed = self.planner.candidates(view)
            if self.finishing:
                proposed = spread_steps(whole, proposed, self.options.finish_gap)
            self._check_sizes(proposed)
            candidates = self._new_arrangements(self.recovery.allowed(proposed))
            self.failures.clear()
            self.spend = DecisionSpend(len(self.home), self.options.fewer_moves_after)
            planned = len(self.executor.plan)
            decided = self._decide(view, candidates, decision)
            if self.pace is not None:
                placed = sum(not b for b in self.records[-1].to_buffer) if decided else 0
                self.pace.decided(self.options.clock() - clock, placed, self.finishing)
            if decided:
                added = self.executor.plan[planned:]
                yield planned_step(self.cache, len(self.records) - 1, self.records[-1], added)
                continue
            if not self.finishing and self.deadline.soft_passed() and not self.deadline.expired():
                self._finish()  # the soft limit cut the decision short: finish from here
                continue
            if self.deadline.passed():
                status = Status.TIMEOUT
                diagnosis.append(f"max_time reached with {len(view.remaining)} object(s) left")
                break
            status = Status.INFEASIBLE
            left = ", ".join(self.cache.show(o) for o in view.remaining)
            diagnosis.append(
                f"no candidate step could be grounded and executed; "
                f"{len(view.remaining)} object(s) left ({left})"
            )
            diagnosis.extend(dict.fromkeys(self.failures.reasons))
            break
        if self.options.progress is not None:
            self.options.progress(len(self.goals) - len(self.view().remaining), len(self.goals))
        summary = RunSummary(
            status,
            tuple(diagnosis),
            time.perf_counter() - start,
            self.executor.motion_time,
            tuple(self.executor.plan),
            self.executor.cost,
        )
        return build_solution(self.cache, summary, self.records)

    def _family_spent(self, step: Step, arms: tuple[str, ...], mode: MotionMode) -> bool:
        return self.spend.blocked(step, arms, mode)

    def _pace(self, remaining: int) -> None:
        """Before a decision of ``remaining`` objects: go back to the normal search when the
        finish's pace leaves room for a normal decision; else set the soft limit at the
        reserve the objects need, and finish when it has passed."""
        if self.pace is None:
            return
        if self.finishing and self.pace.room_for_normal(self.deadline.left(), remaining):
            self._resume()
        if not self.finishing:
            self.deadline.reserve(self.pace.reserve(remaining))
            if self.deadline.soft_passed():
                self._finish()

    def _finish(self) -> None:
        """Start the anytime finish (see :mod:`~solvers.sdar.spending`): no soft limit any
        more, the first grounding found is taken."""
        self.finishing = True
        self.deadline.reserve(float("inf"))
        self.grounder.options = finishing_options(self._normal_grounding[0])
        self.grounder.first_found = True
        self.grounder.assigner.by_plane = True
        LOG.info(
            "finishing with steps of at most %d move(s), %.1f s left",
            self.options.finish_moves,
            self.deadline.left(),
        )

    def _resume(self) -> None:
        """Leave the finish: the normal search again (its soft limit is set by the caller)."""
        self.finishing = False
        self.grounder.options, self.grounder.first_found = self._normal_grounding
        self.grounder.assigner.by_plane = False
        LOG.info("back to the normal search, %.1f s left", self.deadline.left())

    def _check_sizes(self, candidates: Sequence[Step]) -> None:
        """Every candidate holds at most one move per arm.

        Raises:
            ParameterError: the task planner proposed a step of more moves than arms.
        """
        for step in candidates:
            if len(step.moves) > len(self.home):
                raise ParameterError(
                    f"task planner {self.planner.name!r} proposed a step of {len(step.moves)} "
                    f"moves ({', '.join(map(self.cache.show, step.objects))}) for a cell of "
                    f"{len(self.home)} arm(s)"
                )

    def _arrangement(self, at_goal: Sequence[str] = ()) -> frozenset[tuple[str, str]]:
        """The current arrangement (object, pose), with the objects ``at_goal`` moved to their
        goals."""
        current = self.cache.current_poses()
        current.update({o: self.goals[o] for o in at_goal})
        return frozenset(current.items())

    def _new_arrangements(self, candidates: Sequence[Step]) -> list[Step]:
        """The candidates less those that only move objects to their goals and so would
        recreate an arrangement met before (undoing the steps since then: a cycle)."""
        return [
            s
            for s in candidates
            if any(m.to_buffer for m in s.moves) or self._arrangement(s.objects) not in self.visited
        ]

    def _decide(self, view: TaskView, candidates: Sequence[Step], decision: Decision) -> bool:
        """Execute one step: a candidate that brings an object to its goal if any works, with
        the first grasps and then with more (:meth:`_wider`); otherwise an eviction (dead-end
        recovery); otherwise a candidate that only buffers."""
        productive = [s for s in candidates if s.progress > 0]
        if self._step(view, productive, decision) is not None:
            return True
        if productive and self._wider(view, productive, decision):
            return True
        if self.recovery.budget_left:
            evictions = self.recovery.candidates(view)
            evicted = self._step(view, evictions, decision, commit=False) if evictions else None
            if evicted is not None:
                self.recovery.executed(evicted)
                return True
        return self._step(view, [s for s in candidates if s.progress == 0], decision) is not None

    def _wider(self, view: TaskView, productive: Sequence[Step], decision: Decision) -> bool:
        """No candidate toward the goals works with the first grasps and some object is boxed
        in: the same candidates with more grasps per object (:meth:`Recovery.wider`), for this
        decision only."""
        wider = self.recovery.wider(view)
        if wider is None or self.deadline.passed():
            return False
        narrow = self.grounder.options
        self.grounder.options = wider
        try:
            return self._step(view, productive, decision) is not None
        finally:
            self.grounder.options = narrow

    def _step(
        self, view: TaskView, candidates: Sequence[Step], decision: Decision, commit: bool = True
    ) -> Step | None:
        """Execute the best grounding whose motions exist; returns its step (``None`` when
        none could be executed). With a quick motion stream, up to
        ``quick_attempts`` groundings of the best rank are tried with it first (a cheap
        motion for another grounding beats the fallbacks of the motion planner for the
        first one); then every grounding with the full motion planner."""
        has_quick = self.voc.quick_motion in self.cache.streams
        ladder = QuickLadder(self.options.quick_attempts if has_quick else 0)
        tried = 0
        while not self.deadline.passed():
            mode = ladder.mode
            groundings = self.grounder.select(self.spend.allowed(candidates), mode)
            if mode is MotionMode.QUICK:
                if ladder.best_rank is None and groundings:
                    ladder.best_rank = groundings[0].step.rank
                if not groundings or groundings[0].step.rank != ladder.best_rank:
                    ladder.left = 0  # the best rank is used up: the full motion planner
                    continue
            if not groundings or self.deadline.passed():  # no motion started past the limit
                return None
            g = groundings[0]
            key = self.grounder.key(g.step, g.arms, g.options)
            after = dict(self.cache.current_poses())
            after.update((m.obj, o.target) for m, o in zip(g.step.moves, g.options, strict=True))
            if frozenset(after.items()) in self.visited:  # back to an earlier arrangement
                self.tabu.add(key, MotionMode.FULL)
                continue
            tried += 1
            record = TaskRecord(
                g.step.kind, g.step.objects, g.arms, tuple(m.to_buffer for m in g.step.moves)
            )
            attempt = self.options.clock()
            ok = self.executor.execute(g, record, mode)
            if self.pace is not None:
                self.pace.attempted(self.options.clock() - attempt, ok, self.finishing)
            record.tried = tried
            record.motion_time = self.executor.motion_time - decision.motion_time
            record.selection_time = time.perf_counter() - decision.start - record.motion_time
            if ok:
                self.records.append(record)
                if commit:
                    self.planner.commit(g.step, view)
                return g.step
            self.tabu.add(key, mode)
            self.spend.failed(g.step, g.arms, mode)
            if mode is MotionMode.QUICK:
                ladder.left -= 1
        return None
