"""Fluent streams see the state of the plan step that uses their output.

Two unit-wide blocks on a line: ``a`` at 0 must end at 5, where ``b`` rests. ``b`` has to slide
aside (to a sampled pose) first; ``a``'s slide is planned by a ``:fluents (atpose)`` stream that
refuses a sweep through another block. In the initial state ``b`` sits on ``a``'s path, so a
solver that calls the stream with the initial state's facts finds no plan; one that calls it
with the facts of the step (``b`` already aside) does.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import pytest

from sdar_tamp.language.formula_model import Atom
from sdar_tamp.language.generators import from_fn, from_gen_fn
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Solution
from solvers.solve import solve
from solvers.stream_planning.fluents import fluent_plan
from solvers.stream_planning.optimistic import OptResult
from solvers.stream_planning.preimage import PlanCheck

DOMAIN = """
(define (domain slide)
  (:requirements :strips :negative-preconditions :derived-predicates)
  (:predicates (block ?b) (region ?r) (pose ?b ?p) (contained ?b ?p ?r) (atpose ?b ?p)
               (motion ?b ?p1 ?p2 ?t) (occupied ?p))
  (:derived (occupied ?p) (exists (?b) (atpose ?b ?p)))
  (:action slide :parameters (?b ?p1 ?p2 ?t)
    :precondition (and (atpose ?b ?p1) (pose ?b ?p2) (motion ?b ?p1 ?p2 ?t)
                       (not (occupied ?p2)))
    :effect (and (atpose ?b ?p2) (not (atpose ?b ?p1)))))
"""
STREAMS = """
(define (stream slide)
  (:stream sample-pose :inputs (?b ?r) :domain (and (block ?b) (region ?r))
    :outputs (?p) :certified (and (pose ?b ?p) (contained ?b ?p ?r)))
  (:stream plan-slide :inputs (?b ?p1 ?p2) :domain (and (pose ?b ?p1) (pose ?b ?p2))
    :fluents (atpose) :outputs (?t) :certified (motion ?b ?p1 ?p2 ?t)))
"""
INIT = [
    ("block", "a"),
    ("block", "b"),
    ("region", "aside"),
    ("pose", "a", 0.0),
    ("atpose", "a", 0.0),
    ("pose", "a", 5.0),
    ("pose", "b", 5.0),
    ("atpose", "b", 5.0),
]
GOAL = ("atpose", "a", 5.0)
WIDTH = 1.0  # [m] every block; two blocks overlap when their centres are closer than this


@dataclass(frozen=True)
class Sweep:
    """A block sliding from ``start`` to ``end`` [m]."""

    block: str
    start: float
    end: float


def sweep_hits(sweep: Sweep, x: float) -> bool:
    """Does a block resting at ``x`` [m] overlap the swept interval?"""
    lo, hi = sorted((sweep.start, sweep.end))
    return lo - WIDTH < x < hi + WIDTH


class Samplers:
    """The stream map, recording what the fluent stream was asked."""

    def __init__(self) -> None:
        self.calls: list[tuple[str, float, float, frozenset[tuple[Any, ...]]]] = []

    def plan_slide(
        self, b: str, p1: float, p2: float, fluents: list[tuple[Any, ...]]
    ) -> tuple[Sweep] | None:
        self.calls.append((b, p1, p2, frozenset(fluents)))
        sweep = Sweep(b, p1, p2)
        others = [f[2] for f in fluents if f[0] == "atpose" and f[1] != b]
        return None if any(sweep_hits(sweep, x) for x in others) else (sweep,)

    def stream_map(self) -> dict[str, Any]:
        def aside(b: str, r: str) -> Iterator[tuple[float]]:
            for k in itertools.count():
                yield (10.0 + k,)

        return {"sample-pose": from_gen_fn(aside), "plan-slide": from_fn(self.plan_slide)}


def replay(solution: Solution) -> dict[str, float]:
    """Independent check: every sweep is the slide's and clear of the blocks *at that step*."""
    assert solution.plan is not None
    poses = {"a": 0.0, "b": 5.0}
    for action in solution.plan:
        assert action.name == "slide"
        b, p1, p2, sweep = action.args
        assert poses[b] == p1 and sweep == Sweep(b, p1, p2)
        for other, x in poses.items():
            assert other == b or not sweep_hits(sweep, x), (action, other, x)
        poses[b] = p2
    assert poses["a"] == 5.0
    return poses


@pytest.mark.parametrize("algorithm", ["incremental", "focused", "binding", "adaptive"])
def test_fluent_stream_sees_the_state_of_its_step(algorithm: str) -> None:
    samplers = Samplers()
    problem = PDDLProblem(DOMAIN, {}, STREAMS, samplers.stream_map(), INIT, GOAL)
    solution = solve(problem, algorithm=algorithm, max_time=20, verbose=False)
    assert solution.solved, solution.diagnosis
    final = replay(solution)
    assert [a.args[0] for a in solution.plan or []] == ["b", "a"]
    # a's slide was planned among the blocks as they are after b's slide, not initially
    step_state = frozenset({("atpose", "a", 0.0), ("atpose", "b", final["b"])})
    assert ("a", 0.0, 5.0, step_state) in samplers.calls
    b_slide = ("b", 5.0, final["b"], frozenset({("atpose", "a", 0.0), ("atpose", "b", 5.0)}))
    assert b_slide in samplers.calls


def _result(name: str, inputs: tuple[str, ...], outputs: tuple[str, ...], cert: str) -> OptResult:
    domain = tuple(Atom("pose", (n,)) for n in inputs)
    certified = (Atom(cert, (*inputs, *outputs)), *(Atom("pose", (o,)) for o in outputs))
    return OptResult(name, inputs, outputs, domain, certified, 1, "stream")


def test_fluent_plan_orders_producers_of_fluent_placeholders_first() -> None:
    """The motion of step 1 sees b at the placeholder pose #o0 that step 0 moved it to, so the
    pose sampler moves before it; the motion's state is the one before step 1."""
    motion = _result("motion", ("p0",), ("#o1",), "path")
    pose = _result("sample", (), ("#o0",), "spot")
    init = frozenset({Atom("at", ("b", "p5")), Atom("at", ("a", "p0"))})
    after = frozenset({Atom("at", ("b", "#o0")), Atom("at", ("a", "p0"))})
    check = PlanCheck(
        True,
        None,
        frozenset(),
        after,
        states=(init, after, after),
        supports=(
            frozenset({Atom("spot", ("#o0",))}),
            frozenset({Atom("path", ("p0", "#o1"))}),
            frozenset(),
        ),
    )
    ordered = fluent_plan([motion, pose], check, {"motion": ("at",)})
    assert [r.external for r in ordered.stream_plan] == ["sample", "motion"]
    assert ordered.fluents == {1: tuple(sorted(after, key=str))}


def test_fluent_plan_uses_the_step_of_a_descendant() -> None:
    """A fluent result whose own facts no step uses takes the state of its descendant's use."""
    motion = _result("motion", ("p0",), ("#o1",), "path")
    check_result = OptResult(
        "check", ("#o1",), (), (Atom("pose", ("#o1",)),), (Atom("safe", ("#o1",)),), 2, "stream"
    )
    s0, s1 = frozenset({Atom("at", ("x",))}), frozenset({Atom("at", ("y",))})
    check = PlanCheck(
        True,
        None,
        frozenset(),
        s1,
        states=(s0, s1, s1),
        supports=(frozenset(), frozenset({Atom("safe", ("#o1",))}), frozenset()),
    )
    ordered = fluent_plan([motion, check_result], check, {"motion": ("at",)})
    assert ordered.fluents == {0: (Atom("at", ("y",)),)}
