"""The ``sdar solve`` path imports no plotting or cluster library."""

from __future__ import annotations

import subprocess
import sys

HEAVY = ("matplotlib", "plotly", "ray", "pandas", "ompl")


def test_solve_path_leaves_heavy_libraries_unimported() -> None:
    code = (
        "import sys\n"
        "import sdar_tamp.cli, sdar_tamp.app, solvers.solve, streams.stream_map\n"
        "import streams.motion.ladder\n"
        f"print(','.join(m for m in {HEAVY!r} if m in sys.modules))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert out.stdout.strip() == ""
