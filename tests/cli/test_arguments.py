"""The shared argument rules: API checks name the parameter, argparse types name the range."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pytest

from sdar_tamp.arguments import (
    COST_BOUND,
    COUNT,
    FPS,
    MAX_TIME,
    SEED,
    TIME_LIMIT,
    Integer,
    Real,
    optional,
    output_file,
    output_folder,
)
from sdar_tamp.errors import ParameterError


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, 0, -1.0, "3", True, None])
def test_time_limit_must_be_finite_and_positive(value: object) -> None:
    with pytest.raises(ParameterError, match=r"^time_limit must be a finite number > 0 \[s\]"):
        TIME_LIMIT.check("time_limit", value)


def test_accepted_values_come_back_as_floats_or_ints() -> None:
    assert TIME_LIMIT.check("t", 2) == 2.0 and isinstance(TIME_LIMIT.check("t", 2), float)
    assert TIME_LIMIT.check("t", np.float64(0.5)) == 0.5
    assert MAX_TIME.check("max_time", math.inf) == math.inf
    assert COST_BOUND.check("success_cost", 0) == 0.0
    assert SEED.check("seed", np.int64(7)) == 7 and type(SEED.check("seed", np.int64(7))) is int
    assert COUNT.check("workers", 1) == 1
    assert optional(FPS, "fps", None) is None and optional(FPS, "fps", 4) == 4.0


@pytest.mark.parametrize(
    ("rule", "value", "message"),
    [
        (MAX_TIME, math.nan, r"max_time must be a number > 0 \[s\] or inf, got nan"),
        (MAX_TIME, -math.inf, "max_time must be"),
        (COST_BOUND, -1, "max_time must be a number >= 0 or inf, got -1"),
        (SEED, -5, "max_time must be an integer >= 0, got -5"),
        (SEED, 1.0, "max_time must be an integer >= 0, got 1.0"),
        (SEED, False, "max_time must be an integer >= 0, got False"),
        (COUNT, 0, "max_time must be an integer >= 1, got 0"),
        (FPS, 0.0, r"max_time must be a finite number > 0 \[1/s\], got 0.0"),
        (Real(1.0, closed=True), 0.5, "max_time must be a finite number >= 1, got 0.5"),
    ],
)
def test_refusals_name_the_parameter_and_the_range(
    rule: Real | Integer, value: object, message: str
) -> None:
    with pytest.raises(ParameterError, match=message):
        rule.check("max_time", value)


@pytest.mark.parametrize(
    ("rule", "text", "message"),
    [
        (TIME_LIMIT, "nan", r"expected a finite number > 0 \[s\], got 'nan'"),
        (TIME_LIMIT, "inf", "got 'inf'"),
        (TIME_LIMIT, "0", "got '0'"),
        (TIME_LIMIT, "soon", "got 'soon'"),
        (SEED, "-5", "expected an integer >= 0, got '-5'"),
        (SEED, "1.5", "got '1.5'"),
        (COUNT, "0", "expected an integer >= 1, got '0'"),
        (FPS, "-2", r"expected a finite number > 0 \[1/s\], got '-2'"),
    ],
)
def test_argparse_types_refuse_with_the_range(
    rule: Real | Integer, text: str, message: str
) -> None:
    with pytest.raises(argparse.ArgumentTypeError, match=message):
        rule.parse(text)


def test_argparse_types_parse_good_text() -> None:
    assert TIME_LIMIT.parse("2.5") == 2.5
    assert SEED.parse("0") == 0 and COUNT.parse("12") == 12
    assert MAX_TIME.parse("inf") == math.inf


def test_output_file_rules(tmp_path: Path) -> None:
    target = tmp_path / "new" / "deeper" / "plan.json"
    assert output_file(target, suffixes=(".json",)) == target  # missing folders are fine
    with pytest.raises(ParameterError, match=r"--output: expected a file ending in \.json, got"):
        output_file(tmp_path / "plan.txt", suffixes=(".json",))
    existing = tmp_path / "plan.json"
    existing.write_text("{}")
    with pytest.raises(ParameterError, match="exists; pass --force to replace it"):
        output_file(existing)
    assert output_file(existing, force=True) == existing
    with pytest.raises(ParameterError, match="is a folder"):
        output_file(tmp_path, force=True)
    with pytest.raises(ParameterError, match=r"plan\.json' is a file, not a folder"):
        output_file(existing / "sub" / "x.json", name="-o")
    assert output_file(tmp_path / "PIC.PNG", suffixes=(".png",)).name == "PIC.PNG"


def test_output_folder_rules(tmp_path: Path) -> None:
    assert output_folder(tmp_path / "a" / "b") == tmp_path / "a" / "b"
    afile = tmp_path / "f.csv"
    afile.write_text("")
    with pytest.raises(ParameterError, match=r"--out: expected a folder, .*f\.csv' is a file"):
        output_folder(afile, name="--out")
    with pytest.raises(ParameterError, match="is a file, not a folder"):
        output_folder(afile / "sub")
