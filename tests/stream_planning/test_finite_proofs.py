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


def test_a_test_failing_on_every_pair_ends_infeasible_and_is_named() -> None:
    solution = solve(_problem(4, cfree=False), algorithm="incremental", verbose=False)
    assert solution.status is Status.INFEASIBLE, solution.diagnosis
    stats = solution.streams["test-cfree"]
    failed = stats.calls - stats.successes
    assert failed > 0
    assert f"test 'test-cfree' failed {failed} of {stats.calls} call(s)" in solution.diagnosis


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
