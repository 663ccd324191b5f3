"""Two arms swap two objects through a buffer pose or a hand-over.

Run: ``python examples/dual_arm_swap.py -a focused`` (``-a``: algorithm, ``-u``: unit costs).
"""

from __future__ import annotations

import logging
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # run from a source checkout

from domains.dual_arm_swap.samplers import make_problem
from solvers.solution import Solution, print_solution
from solvers.solve import create_parser, solve


def main(argv: list[str] | None = None) -> Solution:
    """Parse ``argv``, solve, print the plan; returns the solution (for tests)."""
    parser = create_parser()
    parser.add_argument("--seed", type=int, default=0, help="sampler seed (default: 0)")
    parser.add_argument("--max-time", type=float, default=30, help="[s] (default: %(default)s)")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    problem = make_problem(seed=args.seed)
    solution = solve(
        problem,
        algorithm=args.algorithm,
        unit_costs=args.unit,
        max_time=args.max_time,
        seed=args.seed,
        verbose=False,
    )
    print_solution(solution)
    return solution


if __name__ == "__main__":
    main()
