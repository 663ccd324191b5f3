"""Plan JSON that is nested too deep or holds numbers Python will not convert: located
:class:`PlanFileError`, never a ``RecursionError`` or ``ValueError``."""

from __future__ import annotations

from pathlib import Path

import pytest

from sdar_tamp.plan_file import MAX_DEPTH, PlanFileError
from sdar_tamp.plan_reading import load_plan


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "plan.json"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("depth", [MAX_DEPTH + 1, 500, 100_000])
def test_deep_lists(tmp_path: Path, depth: int) -> None:
    path = _write(tmp_path, '{"format":\n  ' + "[" * depth + "]" * depth + "}")
    with pytest.raises(PlanFileError) as info:
        load_plan(path)
    # the root object is level 1; the list one level too deep opens at column 3 + MAX_DEPTH - 1
    assert str(info.value) == (
        f"{path}:2:{3 + MAX_DEPTH - 1}: lists and objects nested deeper than {MAX_DEPTH} levels"
    )


def test_brackets_inside_strings_do_not_count(tmp_path: Path) -> None:
    text = '{"a": "[[[[{{\\"", "b": ' + '{"k": ' * (MAX_DEPTH + 5) + "1" + "}" * (MAX_DEPTH + 5)
    path = _write(tmp_path, text + "}")
    with pytest.raises(PlanFileError, match=rf":1:{24 + 6 * (MAX_DEPTH - 1)}: lists and objects"):
        load_plan(path)


def test_nesting_at_the_limit_reaches_the_shape_checks(tmp_path: Path) -> None:
    path = _write(tmp_path, '{"format": ' + "[" * (MAX_DEPTH - 1) + "]" * (MAX_DEPTH - 1) + "}")
    with pytest.raises(PlanFileError, match="missing key"):
        load_plan(path)


def test_integer_with_too_many_digits(tmp_path: Path) -> None:
    path = _write(tmp_path, '{"version": ' + "9" * 5000 + "}")
    with pytest.raises(PlanFileError, match=r"plan\.json: invalid JSON: .*digits"):
        load_plan(path)
