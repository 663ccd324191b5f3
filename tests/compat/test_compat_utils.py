"""``pddlstream.utils`` helpers and the PDDLStream constants a program relies on."""

from __future__ import annotations

import io
import math
from pathlib import Path

import pytest

from sdar_tamp.compat.pddlstream import (
    And,
    Fact,
    Or,
    Output,
    Profiler,
    find_unique,
    get_file_path,
    get_length,
    inclusive_range,
    is_plan,
    read,
    read_pddl_pair,
    retime_plan,
    safe_zip,
    str_eq,
    str_from_object,
    user_input,
)
from sdar_tamp.compat.pddlstream.__main__ import main as runner_main
from sdar_tamp.compat.pddlstream.algorithms.downward import get_cost_scale, set_cost_scale
from sdar_tamp.compat.pddlstream.language.temporal import compute_duration, get_end


def test_files_next_to_a_module(tmp_path: Path) -> None:
    (tmp_path / "domain.pddl").write_text("(define (domain d))")
    (tmp_path / "problem.pddl").write_text("(define (problem p))")
    here = str(tmp_path / "run.py")
    assert get_file_path(here, "domain.pddl") == str(tmp_path / "domain.pddl")
    assert read(tmp_path / "domain.pddl") == "(define (domain d))"
    assert read_pddl_pair(here) == ["(define (domain d))", "(define (problem p))"]


def test_safe_zip_and_find_unique_refuse_bad_input() -> None:
    assert list(safe_zip([1, 2], "ab")) == [(1, "a"), (2, "b")]
    with pytest.raises(ValueError, match="different lengths"):
        safe_zip([1], [1, 2])
    assert find_unique(lambda x: x > 2, [1, 3]) == 3
    with pytest.raises(RuntimeError):
        find_unique(lambda x: x > 0, [1, 3])


def test_str_from_object_is_stable() -> None:
    assert str_from_object({"b": {2, 1}, "a": [1.23456, (True,)]}, ndigits=2) == (
        "{'a': [1.23, (True)], 'b': {1, 2}}"
    )
    assert str_eq("Pick", "pick") and not str_eq("Pick", "pick", ignore_case=False)


def test_user_input_returns_empty_at_end_of_input(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("sys.stdin", io.StringIO(""))
    assert user_input("Continue?") == ""
    monkeypatch.setattr("sys.stdin", io.StringIO("yes\n"))
    assert user_input("Continue?") == "yes"


def test_profiler_prints_the_top_functions(capsys: pytest.CaptureFixture[str]) -> None:
    with Profiler(field="cumtime", num=3):
        sum(range(1000))
    assert "function calls" in capsys.readouterr().out
    with pytest.raises(ValueError, match="field"):
        Profiler(field="calls")


def test_formula_and_plan_helpers() -> None:
    assert And(("a",)) == ("a",) and And(("a",), ("b",)) == ("and", ("a",), ("b",))
    assert Or(("a",), ("b",))[0] == "or"
    assert Output(1, 2) == (1, 2) and Fact("on", [1, 2]) == ("on", 1, 2)
    assert is_plan([]) and not is_plan(None) and not is_plan(False)
    assert get_length(None) == math.inf and get_length([("a", ())]) == 1
    timed = retime_plan([("move", (1, 2)), ("pick", (3,))])
    assert timed is not None and get_end(timed[1]) == 2 and compute_duration(timed) == 2
    assert inclusive_range(0, 1, 0.5) == [0, 0.5, 1]
    with pytest.raises(ValueError, match="step"):
        inclusive_range(0, 1, 0)


def test_cost_scale_is_settable_and_checked() -> None:
    before = get_cost_scale()
    try:
        set_cost_scale(100)
        assert get_cost_scale() == 100
        with pytest.raises(ValueError, match="cost_scale"):
            set_cost_scale(0)
    finally:
        set_cost_scale(before)


def test_runner_usage(capsys: pytest.CaptureFixture[str]) -> None:
    assert runner_main([]) == 2
    assert runner_main(["--help"]) == 0
    assert "usage" in capsys.readouterr().out
