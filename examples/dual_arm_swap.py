"""Two arms swap two objects through a buffer pose or a hand-over.

Run: ``python examples/dual_arm_swap.py -a focused`` (``-a``: algorithm, ``-u``: unit costs).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout

from domains.dual_arm_swap.samplers import make_problem
from solvers.solution import Solution
from solvers.solve import solve_from_command_line


def main(argv: list[str] | None = None) -> Solution:
    """Parse ``argv``, solve, print the plan; returns the solution (for tests)."""
    return solve_from_command_line(make_problem, argv, default_max_time=30)


if __name__ == "__main__":
    main()
