"""``solve(verbose=True)`` with a stream algorithm prints one line per round and the final
counts on standard output; a terminal also gets a transient "searching" line, anything else
the lines only."""

from __future__ import annotations

import io
import re
from pathlib import Path

import pytest
from stream_helpers import ALGORITHMS

from sdar_tamp.language.generators import from_gen_fn, from_test
from sdar_tamp.language.problem import PDDLProblem
from solvers.solution import Status
from solvers.solve import solve

NARROW = Path(__file__).resolve().parents[2] / "domains" / "infeasible"
ROUND = re.compile(
    r"^round (\d+) level (\d+): (.+), calls \+(\d+) \((\d+)\), facts \+(\d+) \((\d+)\), "
    r"(\d+\.\d{3}) s \(world (\d+\.\d{3}), grounding (\d+\.\d{3}), search (\d+\.\d{3}), "
    r"sampling (\d+\.\d{3})\)$"
)


def _problem(cfree: bool) -> PDDLProblem:
    def sample_pose(block: str, region: str):  # type: ignore[no-untyped-def]
        if region == "goal":
            yield from ((float(k),) for k in range(3))

    init: list[tuple[object, ...]] = [("handempty",), ("region", "table"), ("region", "goal")]
    for block, x in (("A", -10.0), ("B", -20.0)):
        init += [("block", block), ("pose", x), ("blockpose", block, x), ("atpose", block, x)]
        init += [("contained", block, x, "table")]
    return PDDLProblem(
        (NARROW / "domain.pddl").read_text(encoding="utf-8"),
        {},
        (NARROW / "stream.pddl").read_text(encoding="utf-8"),
        {
            "sample-pose": from_gen_fn(sample_pose),
            "test-cfree": from_test(lambda b, p, b2, p2: b == b2 or (cfree and p != p2)),
        },
        init,
        ("and", ("in", "A", "goal"), ("in", "B", "goal")),
    )


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_every_round_prints_one_line_then_the_counts(
    algorithm: str, capsys: pytest.CaptureFixture[str]
) -> None:
    solution = solve(_problem(cfree=True), algorithm=algorithm, max_time=60, verbose=True)
    assert solution.status is Status.SOLVED
    out = capsys.readouterr().out
    assert "\r" not in out  # not a terminal: lines only
    lines = out.splitlines()
    rounds = [ROUND.match(line) for line in lines]
    numbers = [int(m.group(1)) for m in rounds if m]
    assert numbers == list(range(1, int(solution.statistics["iterations"]) + 1))
    calls = [int(m.group(5)) for m in rounds if m]
    assert calls == sorted(calls)  # running totals
    assert lines[len(numbers)].startswith(f"{algorithm}: solved after {len(numbers)} round(s)")
    for name, stats in solution.streams.items():
        assert f"  {name}: {stats.calls} call(s), {stats.successes} success(es)" in out


def test_an_infeasible_run_says_why(capsys: pytest.CaptureFixture[str]) -> None:
    solution = solve(_problem(cfree=False), algorithm="focused", max_time=60, verbose=True)
    assert solution.status is Status.INFEASIBLE
    out = capsys.readouterr().out
    assert "nothing is left out: infeasible" in out
    assert "focused: infeasible after" in out
    for reason in solution.diagnosis:
        assert f"  why: {reason}" in out


def test_quiet_prints_nothing(capsys: pytest.CaptureFixture[str]) -> None:
    solve(_problem(cfree=True), algorithm="adaptive", max_time=60, verbose=False)
    assert capsys.readouterr().out == ""


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_terminal_also_sees_what_the_search_is_doing(monkeypatch: pytest.MonkeyPatch) -> None:
    terminal = _Terminal()
    monkeypatch.setattr("sys.stdout", terminal)
    solve(_problem(cfree=True), algorithm="binding", max_time=60, verbose=True)
    text = terminal.getvalue()
    assert "\r\x1b[Kround 1 level 0: searching..." in text
    # each transient line is cleared before the round's line
    visible = re.sub(r"\r\x1b\[K[^\n\r]*(?=\r\x1b\[K)", "", text).replace("\r\x1b[K", "")
    assert "searching..." not in visible
    assert ROUND.match(visible.splitlines()[0])


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_the_round_costs_are_split_into_worlds_grounding_and_search(
    algorithm: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """``world_time`` (building optimistic worlds) and ``grounding_time`` (the planner's
    grounding, part of ``search_time``) are counted, and the summary line gives them."""
    solution = solve(_problem(cfree=True), algorithm=algorithm, max_time=60, verbose=True)
    statistics = solution.statistics
    assert 0.0 < statistics["grounding_time"] <= statistics["search_time"]
    if algorithm == "incremental":  # plans on the real facts: no optimistic world is built
        assert statistics["world_time"] == 0.0
    else:
        assert statistics["world_time"] > 0.0
    assert statistics["world_time"] + statistics["search_time"] <= statistics["time"]
    summary = next(line for line in capsys.readouterr().out.splitlines() if " after " in line)
    assert re.search(
        r"search \d+\.\d{3} s \(grounding \d+\.\d{3} s\), worlds \d+\.\d{3} s", summary
    )


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_each_round_line_splits_its_time_into_world_grounding_search_and_sampling(
    algorithm: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """A round line's parts are that round's shares of the solve's counters: over all rounds
    they add up to the solve's ``world_time``, ``grounding_time``, ``search_time`` minus
    grounding and ``sample_time`` (to the printed precision)."""
    solution = solve(_problem(cfree=True), algorithm=algorithm, max_time=60, verbose=True)
    rounds = [ROUND.match(line) for line in capsys.readouterr().out.splitlines()]
    parts = [[float(m.group(i)) for i in range(9, 13)] for m in rounds if m]
    assert len(parts) == solution.statistics["iterations"]
    statistics = solution.statistics
    totals = (
        statistics["world_time"],
        statistics["grounding_time"],
        statistics["search_time"] - statistics["grounding_time"],
        statistics["sample_time"],
    )
    for column, total in zip(zip(*parts, strict=True), totals, strict=True):
        assert sum(column) == pytest.approx(total, abs=0.0005 * len(parts) + 1e-9)
