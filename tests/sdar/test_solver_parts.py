"""The parts of SDAR-M around the decision loop: tabu lists, the quick-stream ladder, the
deadline and the failure record."""

from __future__ import annotations

from solvers.sdar.attempts import MotionMode, QuickLadder, TabuLists
from solvers.sdar.budget import Deadline
from solvers.sdar.report import Failures
from solvers.sdar.tasks import Move, Step


def test_a_quick_failure_blocks_only_quick_attempts() -> None:
    tabu = TabuLists()
    tabu.add("g1", MotionMode.QUICK)
    assert tabu.blocked("g1", MotionMode.QUICK)
    assert not tabu.blocked("g1", MotionMode.FULL)  # the full planner may still find it
    tabu.add("g2", MotionMode.FULL)
    assert tabu.blocked("g2", MotionMode.FULL) and tabu.blocked("g2", MotionMode.QUICK)
    assert not tabu.blocked("g3", MotionMode.QUICK)


def test_the_ladder_is_quick_while_attempts_are_left() -> None:
    ladder = QuickLadder(2)
    assert ladder.mode is MotionMode.QUICK and ladder.best_rank is None
    ladder.left -= 1
    assert ladder.mode is MotionMode.QUICK
    ladder.left -= 1
    assert ladder.mode is MotionMode.FULL
    assert QuickLadder(0).mode is MotionMode.FULL  # no quick stream: the full one at once


def test_a_deadline_passes_only_once_started() -> None:
    unstarted = Deadline(0.0)
    assert not unstarted.passed()
    started = Deadline(-1.0)  # already over when started
    started.start()
    assert started.passed()
    later = Deadline(3600.0)
    later.start()
    assert not later.passed()


def test_failures_name_objects_arms_and_the_reason() -> None:
    failures = Failures(lambda name: name.upper())
    step = Step((Move("o1"), Move("o2", True)), "pair")
    failures.why(step, ("left", "right"), "no motion")
    assert failures.reasons == ["pair (O1 by LEFT, O2->buffer by RIGHT): no motion"]
    failures.clear()
    assert failures.reasons == []
