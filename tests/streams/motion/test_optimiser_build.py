"""The optimiser is built in a background thread: a process may end while it is building."""

from __future__ import annotations

import subprocess
import sys

PROGRAM = """
import time

from streams.context import WorldContext
from streams.motion.optimiser_build import OptimiserBuild
from streams.motion.optimiser_records import TrajOptOptions

build = OptimiserBuild(WorldContext.load(), TrajOptOptions())
time.sleep(0.05)  # in the build (a few tenths of a second of CPU) when the program ends
"""


def test_a_process_ending_during_a_build_exits_cleanly() -> None:
    # With a daemon build thread, CasADi code still running at interpreter shutdown crashed the
    # process (SIGSEGV / abort, exit status 139 or 134).
    result = subprocess.run(
        [sys.executable, "-c", PROGRAM], capture_output=True, text=True, timeout=600
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert "terminate called" not in result.stderr
