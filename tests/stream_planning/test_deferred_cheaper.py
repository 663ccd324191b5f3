"""Deferred functions that cost more than assumed: the search for a cheaper plan covers the real
facts only, so a plan on new samples never ends it, and a real plan behind an optimistic one is
found."""

from __future__ import annotations

import pytest

from sdar_tamp.language.options import FunctionInfo
from sdar_tamp.language.problem import PDDLProblem
from solvers.solve import solve

SURVEY_DOMAIN = """
(define (domain survey) (:requirements :strips :action-costs)
  (:predicates (Spot ?p) (Known ?p) (Done))
  (:functions (total-cost) (Dist ?p))
  (:action survey :parameters (?p) :precondition (Spot ?p)
    :effect (and (Known ?p) (increase (total-cost) 1)))
  (:action go :parameters (?p) :precondition (Known ?p)
    :effect (and (Done) (increase (total-cost) (Dist ?p)))))
"""
SURVEY_STREAMS = """
(define (stream survey)
  (:stream sample-spot :outputs (?p) :certified (Spot ?p))
  (:function (Dist ?p) (Spot ?p)))
"""


def test_a_cheaper_plan_that_needs_new_samples_leaves_the_dearer_real_plan_standing(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The known spot's plan (assumed cost 1) costs 10 once its distance is evaluated; the
    only cheaper candidate at the level surveys a spot not sampled yet (assumed 2): focused
    returns the known plan without calling the sampler, as binding and adaptive end at a real
    plan."""
    sampled: list[str] = []

    def spots():  # type: ignore[no-untyped-def]
        for k in range(3):
            sampled.append(f"s{k}")
            yield (f"s{k}",)

    problem = PDDLProblem(
        SURVEY_DOMAIN,
        {},
        SURVEY_STREAMS,
        {"sample-spot": lambda: spots(), "dist": lambda p: 10.0 if p == "home" else 0.5},
        [("Spot", "home"), ("Known", "home")],
        ("Done",),
    )
    solution = solve(problem, algorithm="focused", max_time=10, verbose=True, initial_complexity=1)
    assert solution.solved and solution.plan is not None
    assert [a.name for a in solution.plan] == ["go"] and solution.cost == 10.0
    assert sampled == []
    # the search for a cheaper plan covers the real facts only: it finds none
    assert "no plan cheaper than the best real plan" in capsys.readouterr().out


def test_the_search_for_a_cheaper_plan_finds_a_real_one_behind_an_optimistic_one() -> None:
    """home's plan (assumed 1) costs 10 once evaluated. Below 10, the cheapest optimistic plan
    surveys a new sample (assumed 2), but the known spot ``near`` gives a real plan of cost 5:
    the search for a cheaper plan covers the real facts, so that plan is found and returned
    (a plan on new samples would have ended the search with the dearer one), still without
    sampling."""
    sampled: list[str] = []

    def spots():  # type: ignore[no-untyped-def]
        for k in range(3):
            sampled.append(f"s{k}")
            yield (f"s{k}",)

    distances = {"home": 10.0, "near": 5.0}
    problem = PDDLProblem(
        SURVEY_DOMAIN,
        {},
        SURVEY_STREAMS,
        {"sample-spot": lambda: spots(), "dist": lambda p: distances.get(p, 0.5)},
        [("Spot", "home"), ("Known", "home"), ("Spot", "near"), ("Known", "near")],
        ("Done",),
    )
    # a lower bound of every distance: exact for near, 1 elsewhere
    info = {"dist": FunctionInfo(opt_fn=lambda p: 5.0 if p == "near" else 1.0)}
    solution = solve(
        problem, algorithm="focused", stream_info=info, max_time=10, initial_complexity=1
    )
    assert solution.solved and solution.plan is not None
    assert [(a.name, a.args) for a in solution.plan] == [("go", ("near",))]
    assert solution.cost == 5.0
    assert sampled == []
