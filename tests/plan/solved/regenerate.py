"""Write the solved plans the schedule tests start from (the synchronous SDAR plans of three
`paper` instances, seed 0). The scheduler is what those tests check, so they read these
files instead of planning again; run this after a change to the planner or the plan format:

    python tests/plan/solved/regenerate.py
"""

from __future__ import annotations

from pathlib import Path

from sdar_tamp.app.plan_export import plan_file_from_solution
from sdar_tamp.app.problem import rearrangement_problem
from sdar_tamp.app.solving import solve_rearrangement
from sdar_tamp.plan_writing import save_plan
from sdar_tamp.replay import validate_plan
from sdar_tamp.world.instance import load_instance
from sdar_tamp.world.suites import shipped_suite_dir
from solvers.solution import Status
from streams.context import WorldContext
from streams.motion.planner import MotionPlanner

#: The instances, by the role they play in the tests.
INSTANCES = ("R5", "D5", "M2")
HERE = Path(__file__).resolve().parent


def main() -> None:
    ctx = WorldContext.load()
    planner = MotionPlanner(ctx)
    for name in INSTANCES:
        instance = load_instance(shipped_suite_dir("paper") / f"{name}.yaml")
        problem = rearrangement_problem(instance, ctx, planner=planner)
        solution = solve_rearrangement(problem, "sdar", 600.0)
        if solution.status is not Status.SOLVED:
            raise SystemExit(f"{name}: {solution.status}")
        plan = plan_file_from_solution(problem, solution)
        if not validate_plan(instance, plan, ctx.scene).ok:
            raise SystemExit(f"{name}: the plan does not validate")
        print(save_plan(plan, HERE / f"{name}.plan.json"))


if __name__ == "__main__":
    main()
