"""PlanConstraints: skeletons with values, WILD and shared variables; exact; max_cost."""

from __future__ import annotations

import itertools
from collections.abc import Iterator

import pytest

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.generators import from_gen_fn
from sdar_tamp.language.options import WILD, PlanConstraints
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Status
from solvers.solve import solve

LINE = """
(define (domain line)
  (:requirements :strips :equality :negative-preconditions :action-costs)
  (:predicates (block ?b) (pose ?b ?p) (goalpose ?b ?p) (atpose ?b ?p) (done ?b))
  (:functions (total-cost))
  (:action move :parameters (?b ?p1 ?p2)
    :precondition (and (atpose ?b ?p1) (pose ?b ?p2) (not (= ?p1 ?p2)))
    :effect (and (atpose ?b ?p2) (not (atpose ?b ?p1)) (increase (total-cost) 1)))
  (:action finish :parameters (?b ?p)
    :precondition (and (atpose ?b ?p) (goalpose ?b ?p))
    :effect (done ?b)))
"""
STREAMS = """
(define (stream line)
  (:stream sample-pose :inputs (?b) :domain (block ?b)
    :outputs (?p) :certified (pose ?b ?p)))
"""


def _gen(b: str) -> Iterator[tuple[float]]:
    for k in itertools.count(1):
        yield (float(k),)


def _problem() -> PDDLProblem:
    init = [("block", "a"), ("pose", "a", 0.0), ("atpose", "a", 0.0), ("goalpose", "a", 0.0)]
    return PDDLProblem(LINE, {}, STREAMS, {"sample-pose": from_gen_fn(_gen)}, init, ("done", "a"))


@pytest.mark.parametrize("algorithm", ["incremental", "adaptive"])
def test_without_constraints_the_shortest_plan(algorithm: str) -> None:
    plan, cost, _ = solve(_problem(), algorithm=algorithm, max_time=10, verbose=False)
    assert [a.name for a in plan] == ["finish"] and cost == 0


@pytest.mark.parametrize("algorithm", ["incremental", "adaptive"])
def test_skeleton_with_a_shared_variable_is_followed(algorithm: str) -> None:
    skeleton = [("move", ("a", 0.0, "?p")), ("move", ("a", "?p", WILD)), ("finish", ("a", WILD))]
    constraints = PlanConstraints(skeletons=[skeleton])
    plan, cost, _ = solve(
        _problem(), algorithm=algorithm, constraints=constraints, max_time=10, verbose=False
    )
    assert [a.name for a in plan] == ["move", "move", "finish"] and cost == 2
    assert plan[0].args[2] == plan[1].args[1] != 0.0  # the variable: one sampled pose
    assert plan[1].args[2] == 0.0  # back to the goal pose to finish


def test_exact_false_lets_other_actions_in() -> None:
    skeleton = [("move", ("a", 0.0, WILD))]
    exact = PlanConstraints(skeletons=[skeleton], exact=True)
    loose = PlanConstraints(skeletons=[skeleton], exact=False)
    assert solve(_problem(), constraints=exact, max_time=5, verbose=False).plan is None
    plan, _, _ = solve(_problem(), constraints=loose, max_time=10, verbose=False)
    assert plan[0].name == "move" and plan[-1].name == "finish"


def test_one_of_several_skeletons() -> None:
    never = [("move", ("a", 5.0, WILD)), ("finish", ("a", WILD))]  # a is never at 5.0 first
    short = [("finish", ("a", 0.0))]
    plan, _, _ = solve(
        _problem(), constraints=PlanConstraints(skeletons=[never, short]), verbose=False
    )
    assert [a.name for a in plan] == ["finish"]


def test_max_cost_rejects_dearer_plans() -> None:
    skeleton = [("move", ("a", 0.0, WILD)), ("move", (WILD, WILD, 0.0)), ("finish", ("a", WILD))]
    ok = PlanConstraints(skeletons=[skeleton], max_cost=2)
    assert solve(_problem(), constraints=ok, max_time=10, verbose=False).solved
    too_dear = PlanConstraints(skeletons=[skeleton], max_cost=1)
    solution = solve(_problem(), constraints=too_dear, max_time=3, verbose=False)
    assert solution.plan is None and solution.status in (Status.INFEASIBLE, Status.TIMEOUT)


@pytest.mark.parametrize(
    ("skeleton", "message"),
    [
        ([("jump", ("a",))], r"skeletons\[0\]\[0\]: unknown action 'jump'"),
        ([("move", ("a", 0.0))], "action 'move' takes 3 argument"),
        (["move"], r"expected \(action name, args\)"),
    ],
)
def test_bad_skeletons_are_named(skeleton: list, message: str) -> None:
    with pytest.raises(ParameterError, match=message):
        solve(_problem(), constraints=PlanConstraints(skeletons=[skeleton]), verbose=False)


def test_constraints_must_be_plan_constraints() -> None:
    with pytest.raises(ParameterError, match="constraints must be a PlanConstraints"):
        solve(_problem(), constraints=[("finish", ("a", 0.0))], verbose=False)  # type: ignore[arg-type]
