"""``StreamInfo(p_success=0)``: a stream whose effort is infinite is never assumed by the
optimistic algorithms without ``effort_weight`` (as PDDLStream prunes it from its optimistic
instantiation): only its real results count, those of eager calls on real inputs. With
``effort_weight`` it is assumed at a very high effort."""

from __future__ import annotations

import itertools
from collections.abc import Iterator

import pytest

from sdar_tamp.language.generators import from_gen_fn, from_test
from sdar_tamp.language.options import StreamInfo, never_assumed
from sdar_tamp.language.problem import PDDLProblem
from solvers.solve import solve

DOMAIN = """
(define (domain visit)
  (:requirements :strips)
  (:predicates (start ?q) (conf ?q) (safe ?q) (visited))
  (:action visit :parameters (?q) :precondition (and (conf ?q) (safe ?q))
    :effect (visited)))
"""
STREAMS = """
(define (stream visit)
  (:stream sample-conf :inputs (?q) :domain (start ?q) :outputs (?r) :certified (conf ?r))
  (:stream test-safe :inputs (?q) :domain (conf ?q) :certified (safe ?q)))
"""


def _problem(calls: dict[str, int], init: list[tuple[object, ...]]) -> PDDLProblem:
    def sample(q: float) -> Iterator[tuple[float]]:
        for k in itertools.count(1):
            calls["sample-conf"] += 1
            yield (q + k,)

    def safe(q: float) -> bool:
        calls["test-safe"] += 1
        return q >= 2.0

    stream_map = {"sample-conf": from_gen_fn(sample), "test-safe": from_test(safe)}
    return PDDLProblem(DOMAIN, {}, STREAMS, stream_map, init, ("visited",))


INIT: list[tuple[object, ...]] = [("start", 1.0), ("conf", 1.0)]


@pytest.mark.parametrize("algorithm", ["adaptive", "focused", "binding"])
def test_an_assumed_test_lets_the_plan_sample(algorithm: str) -> None:
    calls = dict.fromkeys(("sample-conf", "test-safe"), 0)
    info = {"test-safe": StreamInfo(eager=True)}
    solution = solve(_problem(calls, INIT), algorithm=algorithm, stream_info=info, max_time=30)
    assert solution.plan is not None
    assert calls["sample-conf"] >= 1


@pytest.mark.parametrize("algorithm", ["adaptive", "focused", "binding"])
def test_p_success_zero_is_never_assumed(algorithm: str) -> None:
    calls = dict.fromkeys(("sample-conf", "test-safe"), 0)
    info = {"test-safe": StreamInfo(eager=True, p_success=0)}
    solution = solve(_problem(calls, INIT), algorithm=algorithm, stream_info=info, max_time=30)
    # safe(1.0) is false for real and no sampled conf may be assumed safe: no plan, and the
    # sampler is never asked for one
    assert solution.plan is None
    assert calls == {"sample-conf": 0, "test-safe": 1}


def test_p_success_zero_uses_the_real_results() -> None:
    calls = dict.fromkeys(("sample-conf", "test-safe"), 0)
    info = {"test-safe": StreamInfo(eager=True, p_success=0)}
    init = [*INIT, ("conf", 3.0)]
    solution = solve(_problem(calls, init), algorithm="adaptive", stream_info=info, max_time=30)
    assert solution.plan is not None
    assert [(a.name, tuple(a.args)) for a in solution.plan] == [("visit", (3.0,))]
    assert calls == {"sample-conf": 0, "test-safe": 2}


def test_an_effort_overrides_p_success_zero() -> None:
    assert never_assumed(StreamInfo(p_success=0))
    assert not never_assumed(StreamInfo(p_success=0, effort=2.0))
    assert not never_assumed(StreamInfo(p_success=0.5))
    calls = dict.fromkeys(("sample-conf", "test-safe"), 0)
    info = {"test-safe": StreamInfo(eager=True, p_success=0, effort=2.0)}
    solution = solve(_problem(calls, INIT), algorithm="adaptive", stream_info=info, max_time=30)
    assert solution.plan is not None


def test_p_success_must_lie_in_zero_one() -> None:
    with pytest.raises(ValueError, match=r"p_success must be in \[0, 1\]"):
        StreamInfo(p_success=-0.1)


def test_with_effort_weight_p_success_zero_is_a_last_resort() -> None:
    # efforts weigh on plans: the test is assumed (at 1e9 efforts a result), so a plan may
    # rest on a sampled conf
    calls = dict.fromkeys(("sample-conf", "test-safe"), 0)
    info = {"test-safe": StreamInfo(eager=True, p_success=0)}
    problem = _problem(calls, INIT)
    solution = solve(problem, algorithm="adaptive", stream_info=info, effort_weight=1, max_time=30)
    assert solution.plan is not None
    assert calls["sample-conf"] >= 1
