"""Stream planning features around the cost model: StreamInfo/FunctionInfo options (the
implemented ones quiet, the others warned about), stream-plan efforts and ``effort_weight``,
the adapters' single calls, ``opt_fn`` and anytime improvement."""

from __future__ import annotations

import logging
from typing import Any

import pytest
from line_world import LINE, SAMPLE, counting, line_problem

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.domain_reader import parse_domain
from sdar_tamp.language.formula_model import Atom
from sdar_tamp.language.generators import (
    from_fn,
    from_test,
)
from sdar_tamp.language.options import StreamInfo
from solvers.classical import GroundingError
from solvers.solve import solve


def test_unimplemented_stream_info_options_log_a_warning(
    caplog: pytest.LogCaptureFixture,
) -> None:
    info = {"sample-pose": StreamInfo(simultaneous=True, defer_fn=lambda *a: True)}
    with caplog.at_level(logging.WARNING):
        solution = solve(line_problem(counting()), stream_info=info, verbose=False)
    assert solution.solved
    text = caplog.text
    assert "stream_info['sample-pose'].simultaneous" in text
    assert "stream_info['sample-pose'].defer_fn" in text
    assert "not implemented" in text


def test_supported_stream_info_logs_nothing(caplog: pytest.LogCaptureFixture) -> None:
    info = {"sample-pose": StreamInfo(opt_gen_fn="unique")}
    with caplog.at_level(logging.WARNING):
        assert solve(line_problem(counting()), stream_info=info, verbose=False).solved
    assert "not implemented" not in caplog.text


def test_cost_model_options_are_accepted(caplog: pytest.LogCaptureFixture) -> None:
    info = {"sample-pose": StreamInfo(p_success=0.5, overhead=0.1, eager=True)}
    with caplog.at_level(logging.WARNING):
        assert solve(line_problem(counting()), stream_info=info, verbose=False).solved
    for option in ("p_success", "overhead", "eager"):
        assert f"stream_info['sample-pose'].{option}" not in caplog.text


TWO_SAMPLERS = (
    SAMPLE.rstrip()[:-1]
    + """
  (:stream sample-other :inputs (?b ?r) :domain (and (block ?b) (region ?r))
    :outputs (?p) :certified (and (pose ?b ?p) (contained ?b ?p ?r))))
"""
)


def test_stream_plan_effort_follows_the_cost_model() -> None:
    from solvers.stream_planning.optimistic import OptResult
    from solvers.stream_planning.stream_plans import stream_plan_effort

    def result(name: str, kind: str = "stream") -> OptResult:
        return OptResult(name, (), (), (), (), 0, kind)

    plan = [result("a"), result("b"), result("c"), result("f", "function")]
    info = {
        "a": StreamInfo(effort=5.0),
        "b": StreamInfo(p_success=0.5, overhead=2.0),
        "c": StreamInfo(),
    }
    assert stream_plan_effort(plan, info) == 5.0 + 4.0 + 1.0
    assert stream_plan_effort(plan, info, unit_efforts=True) == 5.0 + 1.0 + 1.0


@pytest.mark.parametrize("algorithm", ["focused", "binding", "adaptive"])
@pytest.mark.parametrize(
    ("costly", "cheap", "value"),
    [("sample-pose", "sample-other", 7.0), ("sample-other", "sample-pose", 5.0)],
)
def test_effort_weight_chooses_the_cheaper_stream(
    algorithm: str, costly: str, cheap: str, value: float
) -> None:
    # both streams certify the same facts; with effort_weight the optimistic plan pays for
    # the effort of the stream behind its facts, so the costly stream is never called
    problem = line_problem(counting(), TWO_SAMPLERS, **{"sample-other": counting(7.0)})
    info = {costly: StreamInfo(effort=100.0)}
    solution = solve(problem, algorithm=algorithm, stream_info=info, effort_weight=1.0,
                     unit_efforts=True, verbose=False)  # fmt: skip
    assert solution.solved
    assert [(a.name, a.args) for a in solution.plan or []] == [("move", ("a", 0.0, value))]
    assert solution.streams[costly].calls == 0
    assert solution.streams[cheap].calls >= 1


def test_effort_weight_is_validated() -> None:
    problem = line_problem(counting(), TWO_SAMPLERS, **{"sample-other": counting(7.0)})
    with pytest.raises(ParameterError, match="effort_weight"):
        solve(problem, effort_weight=-1.0, verbose=False)


def test_action_efforts_count_each_result_once() -> None:
    from solvers.classical import PlanningTask
    from solvers.classical import plan as classical_plan
    from solvers.stream_planning.optimistic import OptimisticWorld, OptResult
    from solvers.stream_planning.stream_plans import ActionEfforts, positive_atoms

    pose = OptResult("sample-pose", ("a", "goal"), ("#o0",), (), (), 1, "stream")
    facts = {
        Atom("pose", ("a", "#o0")): pose,
        Atom("contained", ("a", "#o0", "goal")): pose,
    }
    world = OptimisticWorld(dict.fromkeys(facts, 1), dict(facts), {})
    info = {"sample-pose": StreamInfo(effort=3.0)}
    domain = parse_domain(LINE)
    efforts = ActionEfforts(domain, world, info, 2.0, unit_efforts=False)
    assert efforts("move", ("a", "0", "#o0")) == 6.0  # one result behind the preconditions
    assert efforts("move", ("a", "#o0", "0")) == 0.0  # (pose a 0) is real
    move = domain.action("move")
    binding = {"?b": "a", "?p1": "x", "?p2": "y"}
    assert Atom("pose", ("a", "y")) in positive_atoms(move.precondition, binding)
    assert not any(a.predicate == "unsafe" for a in positive_atoms(move.precondition, binding))
    # the planner adds the extra cost in its search but reports the true cost
    init = frozenset({Atom("atpose", ("a", "0")), Atom("pose", ("a", "0")), *facts})
    objects = dict.fromkeys(("a", "goal", "0", "#o0"), "object")
    task = PlanningTask(domain, objects, init, Atom("atpose", ("a", "#o0")),
                        extra_cost=efforts)  # fmt: skip
    result = classical_plan(task)
    assert result.plan is not None and result.cost == 0.0  # the domain has no action costs
    with pytest.raises(GroundingError, match="extra costs"):
        classical_plan(PlanningTask(domain, objects, init, Atom("atpose", ("a", "#o0")),
                                    extra_cost=lambda n, a: -1.0))  # fmt: skip


def test_action_efforts_match_the_stream_plan_of_each_action() -> None:
    from solvers.stream_planning.optimistic import OptimisticWorld, OptResult
    from solvers.stream_planning.stream_plans import (
        ActionEfforts,
        extract_stream_plan,
        positive_atoms,
        stream_plan_effort,
    )

    # two poses from one sampler, a third from another whose input is the first pose: the
    # results behind a fact are shared between facts and actions, found once per grounding
    first = OptResult("sample-pose", ("a", "goal"), ("#o0",), (), (), 1, "stream")
    pose_a = Atom("pose", ("a", "#o0"))
    second = OptResult("sample-near", ("a", "#o0"), ("#o1",), (pose_a,), (), 2, "stream")
    third = OptResult("sample-pose", ("a", "goal"), ("#o2",), (), (), 1, "stream")
    provenance = {
        pose_a: first,
        Atom("contained", ("a", "#o0", "goal")): first,
        Atom("pose", ("a", "#o1")): second,
        Atom("pose", ("a", "#o2")): third,
    }
    world = OptimisticWorld(dict.fromkeys(provenance, 1), provenance, {})
    info = {"sample-pose": StreamInfo(effort=0.7), "sample-near": StreamInfo(p_success=0.3)}
    domain = parse_domain(LINE)
    efforts = ActionEfforts(domain, world, info, 1.3, unit_efforts=False)
    move = domain.action("move")
    poses = ("0", "#o0", "#o1", "#o2")
    for p1 in poses:
        for p2 in poses:
            binding = {"?b": "a", "?p1": p1, "?p2": p2}
            needed = [a for a in positive_atoms(move.precondition, binding) if a in provenance]
            expected = 1.3 * stream_plan_effort(extract_stream_plan(needed, world), info)
            assert efforts("move", ("a", p1, p2)) == expected  # twice: from the shared table
            assert efforts("move", ("a", p1, p2)) == expected
    assert efforts("move", ("a", "0", "#o1")) == 1.3 * (0.7 + 1 / 0.3)


def test_from_fn_stream_runs_once() -> None:
    calls: list[str] = []

    def once(b: str, r: str) -> tuple[float]:
        calls.append(b)
        return (5.0,)

    solution = solve(line_problem(from_fn(once)), algorithm="incremental", verbose=False)
    assert solution.solved and calls == ["a"]
    assert solution.streams["sample-pose"].calls == 1


def test_from_test_adapter_is_usable_as_a_filter() -> None:
    assert list(from_test(lambda x: x > 0)(1)) == [[()]]
    assert list(from_test(lambda x: x > 0)(-1)) == [[]]


def test_opt_fn_receives_values_and_optimistic_values() -> None:
    from domains.kitchen.samplers import make_problem
    from sdar_tamp.language.options import FunctionInfo
    from solvers.stream_planning.opt_values import OptimisticValue

    seen: list[tuple[Any, ...]] = []

    def optimistic(q1: Any, q2: Any) -> float:
        seen.append((q1, q2))
        return 0.0

    info = {"distance": FunctionInfo(opt_fn=optimistic)}
    solution = solve(make_problem(), algorithm="adaptive", stream_info=info, verbose=False)
    assert solution.solved
    args = [a for pair in seen for a in pair]
    placeholders = [a for a in args if isinstance(a, OptimisticValue)]
    assert placeholders and all(p.stream == "sample-conf" for p in placeholders)
    assert any(isinstance(a, tuple) for a in args)  # the robot's real start configuration


@pytest.mark.parametrize("algorithm", ["incremental", "adaptive"])
def test_anytime_improvement_stops_when_no_cheaper_plan_exists(algorithm: str) -> None:
    from domains.kitchen.samplers import make_problem

    limit = 600.0
    first = solve(make_problem(), algorithm=algorithm, max_time=limit, verbose=False)
    best = solve(make_problem(), algorithm=algorithm, max_time=limit, success_cost=0, verbose=False)
    assert best.solved and best.cost < first.cost
    assert best.cost < 41  # the sink next to the stove (the other gives 48 and more)
    # ended because no cheaper plan was left, long before the (never reached) time limit
    assert best.statistics["time"] < limit / 2
