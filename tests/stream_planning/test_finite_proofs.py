"""Completeness over finite streams: once every stream instance that could matter is exhausted,
every algorithm ends ``infeasible`` (with no ``max_time``), and the diagnosis names the tests
that failed (how often) and the streams that ran dry."""

from __future__ import annotations

from pathlib import Path

import pytest
from stream_helpers import ALGORITHMS

from sdar_tamp.language.generators import from_gen_fn, from_test
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Status
from solvers.solve import solve

NARROW = Path(__file__).resolve().parents[2] / "domains" / "infeasible"


def _problem(poses: int, cfree: bool) -> PDDLProblem:
    """Blocks A and B into region ``goal``, whose sampler has ``poses`` poses per block;
    ``cfree``: whether two blocks at different poses are apart."""
    calls = {"test-cfree": 0}

    def sample_pose(block: str, region: str):  # type: ignore[no-untyped-def]
        if region == "goal":
            yield from ((float(k),) for k in range(poses))

    def test_cfree(b: str, p: float, b2: str, p2: float) -> bool:
        calls["test-cfree"] += 1
        return b == b2 or (cfree and p != p2)

    init: list[tuple[object, ...]] = [("handempty",), ("region", "table"), ("region", "goal")]
    for block, x in (("A", -10.0), ("B", -20.0)):
        init += [("block", block), ("pose", x), ("blockpose", block, x), ("atpose", block, x)]
        init += [("contained", block, x, "table")]
    return PDDLProblem(
        (NARROW / "domain.pddl").read_text(encoding="utf-8"),
        {},
        (NARROW / "stream.pddl").read_text(encoding="utf-8"),
        {"sample-pose": from_gen_fn(sample_pose), "test-cfree": from_test(test_cfree)},
        init,
        ("and", ("in", "A", "goal"), ("in", "B", "goal")),
    )


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_a_sampler_that_yields_nothing_ends_infeasible(algorithm: str) -> None:
    solution = solve(_problem(0, cfree=True), algorithm=algorithm, verbose=False)
    assert solution.status is Status.INFEASIBLE
    assert any("'sample-pose'" in r and "ran dry" in r for r in solution.diagnosis)
    assert not any("time limit" in r for r in solution.diagnosis)


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_a_test_used_negated_under_a_derived_predicate_is_named_with_its_false_count(
    algorithm: str,
) -> None:
    """The domain reads ``cfree`` through ``(not (unsafe ...))``: as in PDDLStream the test is
    negated automatically, and the diagnosis says how often it was false. The table's sampler
    (no plan needs it) is drained once no new plan is found, so every algorithm ends."""
    solution = solve(_problem(4, cfree=False), algorithm=algorithm, max_time=60, verbose=False)
    assert solution.status is Status.INFEASIBLE, solution.diagnosis
    assert any(
        r.startswith("test 'test-cfree' (negate=True) was false on") for r in solution.diagnosis
    )


LINE_DOMAIN = """(define (domain line) (:requirements :strips)
  (:predicates (block ?b) (region ?r) (pose ?b ?p) (in ?b ?p ?r) (at ?b ?p) (holding ?b)
               (free) (done ?b ?r) (safe ?p))
  (:action pick :parameters (?b ?p) :precondition (and (at ?b ?p) (free))
     :effect (and (holding ?b) (not (at ?b ?p)) (not (free))))
  (:action place :parameters (?b ?p ?r)
     :precondition (and (holding ?b) (in ?b ?p ?r) (safe ?p))
     :effect (and (at ?b ?p) (done ?b ?r) (free) (not (holding ?b)))))"""

LINE_STREAMS = """(define (stream line)
  (:stream sample-pose :inputs (?b ?r) :domain (and (block ?b) (region ?r))
     :outputs (?p) :certified (and (pose ?b ?p) (in ?b ?p ?r)))
  (:stream test-safe :inputs (?b ?p) :domain (pose ?b ?p) :certified (safe ?p)))"""


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_a_plain_test_failing_everywhere_ends_infeasible_and_is_named(algorithm: str) -> None:
    """A test whose fact the domain uses positively, false on every pose the finite sampler
    has: no plan, and the diagnosis says how often the test failed."""

    def sample_pose(block: str, region: str):  # type: ignore[no-untyped-def]
        yield from ((x,) for x in (2.0, 2.5))

    problem = PDDLProblem(
        LINE_DOMAIN,
        {},
        LINE_STREAMS,
        {"sample-pose": from_gen_fn(sample_pose), "test-safe": from_test(lambda b, p: p > 2.6)},
        [("free",), ("block", "cup"), ("region", "shelf"), ("at", "cup", 0.0)],
        ("done", "cup", "shelf"),
    )
    solution = solve(problem, algorithm=algorithm, max_time=60, verbose=False)
    assert solution.status is Status.INFEASIBLE, solution.diagnosis
    stats = solution.streams["test-safe"]
    assert stats.calls > 0 and stats.successes == 0
    assert f"test 'test-safe' failed {stats.calls} of {stats.calls} call(s)" in solution.diagnosis


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_the_same_problem_with_room_is_solved(algorithm: str) -> None:
    solution = solve(_problem(4, cfree=True), algorithm=algorithm, max_time=60, verbose=False)
    assert solution.status is Status.SOLVED, solution.diagnosis


def test_a_failing_negated_test_is_named() -> None:
    from sdar_tamp.language.options import StreamInfo

    solution = solve(
        _problem(3, cfree=False),
        algorithm="incremental",
        stream_info={"test-cfree": StreamInfo(negate=True)},
        verbose=False,
    )
    assert solution.status is Status.INFEASIBLE, solution.diagnosis
    assert any(
        r.startswith("test 'test-cfree' (negate=True) was false on") for r in solution.diagnosis
    )


def _slow_sampler_context(delay: float):  # type: ignore[no-untyped-def]
    """A solve context whose pose sampler (20 instances: block x region) takes ``delay`` [s]
    a call and never runs dry."""
    import time

    from solvers.stream_planning.context import SolveContext
    from solvers.stream_planning.options import StreamOptions

    def sample_pose(block: str, region: str):  # type: ignore[no-untyped-def]
        k = 0
        while True:
            time.sleep(delay)
            k += 1
            yield (float(k),)

    init: list[tuple[object, ...]] = [("handempty",)]
    for r in range(10):
        init.append(("region", f"r{r}"))
    for block, x in (("A", -10.0), ("B", -20.0)):
        init += [("block", block), ("pose", x), ("blockpose", block, x), ("atpose", block, x)]
    problem = PDDLProblem(
        (NARROW / "domain.pddl").read_text(encoding="utf-8"),
        {},
        (NARROW / "stream.pddl").read_text(encoding="utf-8"),
        {"sample-pose": from_gen_fn(sample_pose), "test-cfree": from_test(lambda *a: True)},
        init,
        ("placed", "A"),
    )
    context = SolveContext(problem, StreamOptions(enforce_max_time=False))
    context.engine.start()
    context.searched = 100  # the call budget: 100 calls
    return context


def test_a_drain_of_slow_samplers_stops_at_its_time_bound() -> None:
    """Samplers of 0.3 s a call, after a search of no measurable time: the drain stops once
    its calls took DRAIN_SECONDS (0.5 s), after two calls, not after its budget of 100."""
    from solvers.stream_planning.context import DRAIN_SECONDS

    assert DRAIN_SECONDS == 0.5
    context = _slow_sampler_context(0.3)
    assert len(context.engine.instances) >= 20
    assert 1 <= context.drain(0) <= 2
    context.search_seconds = 1.0  # searches of 1 s: a second of calls (ratio 1)
    assert 3 <= context.drain(1) <= 4
    context.runner.close()


def test_a_drain_of_fast_samplers_makes_its_counted_calls() -> None:
    context = _slow_sampler_context(0.0)
    context.searched = 15
    assert context.drain(5) == 15  # the budget, however long the last search took
    context.runner.close()


def test_a_drain_of_called_instances_leaves_the_others_alone() -> None:
    """``called_only``: only instances called before get more calls (the others none)."""
    context = _slow_sampler_context(0.0)
    context.searched = 6
    assert context.drain(50, called_only=True) == 0  # nothing called yet
    first = context.engine.instances[context.engine.instance_keys[0]]
    context.sample(first)
    assert context.drain(50, called_only=True) == 6
    assert first.instance.calls == 7
    others = [context.engine.instances[k] for k in context.engine.instance_keys[1:]]
    assert all(s.instance.calls == 0 for s in others)
    context.runner.close()


def test_a_guessing_drain_stops_at_drain_seconds_whatever_the_searches_took() -> None:
    """Before the first skeleton (``guess``): samplers of 0.3 s a call after searches of 10 s
    get DRAIN_SECONDS (0.5 s: two calls at most), not the searches' share (10 s)."""
    context = _slow_sampler_context(0.3)
    context.search_seconds = 10.0
    assert 1 <= context.drain(0, guess=True) <= 2
    context.runner.close()
