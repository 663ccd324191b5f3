"""The command line's progress bar shows at once and keeps ticking between steps."""

import io
import time

from sdar_tamp.app.summary import ProgressBar


def test_bar_appears_at_once_and_refreshes_without_steps() -> None:
    out = io.StringIO()
    bar = ProgressBar("M1", stream=out, tick=0.01)
    try:
        first = out.getvalue()
        assert first.startswith("\rM1:")  # drawn before any step
        deadline = time.monotonic() + 10.0
        while out.getvalue() == first and time.monotonic() < deadline:
            time.sleep(0.01)
        assert out.getvalue() != first  # the clock ticked with no progress call
        bar(3, 12)
    finally:
        bar.close()
    assert "3/12" in out.getvalue()


def test_the_stage_after_planning_is_named() -> None:
    out = io.StringIO()
    bar = ProgressBar("M1", stream=out, tick=60.0)
    try:
        bar(12, 12)
        bar.stage("scheduling")
        assert out.getvalue().rstrip().endswith("scheduling]")
        bar.stage("validating")
        assert out.getvalue().rstrip().endswith("validating]")
    finally:
        bar.close()


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_bar_is_drawn_on_a_terminal_only() -> None:
    from sdar_tamp.app.summary import terminal_progress

    assert terminal_progress("M1", io.StringIO()) is None  # a pipe or a log file
    out = _Terminal()
    bar = terminal_progress("M1", out)
    assert bar is not None
    try:
        bar(1, 4)
    finally:
        bar.close()
    assert out.getvalue().startswith("\rM1:") and "1/4" in out.getvalue()
