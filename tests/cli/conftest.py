"""Running ``sdar`` in-process in the command-line tests: its exit status and what it printed."""

from __future__ import annotations

import pytest

from sdar_tamp.cli import main


def run_cli(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    """Run ``sdar argv``; return its exit status (argparse's exits included), stdout and stderr."""
    try:
        code = main(argv)
    except SystemExit as exit_:
        code = exit_.code  # type: ignore[assignment]
    captured = capsys.readouterr()
    return int(code), captured.out, captured.err


def refused(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    """Run ``sdar argv``; it must exit with status 2 and one line on stderr, which is returned."""
    code, out, err = run_cli(argv, capsys)
    assert code == 2, (out, err)
    assert out == ""
    line = err.strip()
    assert "\n" not in line and line.startswith("sdar"), line
    return line
