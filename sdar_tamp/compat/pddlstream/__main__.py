"""Run an unmodified PDDLStream program on this compatibility layer.

    python -m sdar_tamp.compat.pddlstream path/to/run.py [program args]
    python -m sdar_tamp.compat.pddlstream -m examples.blocksworld.run [program args]

The alias (:mod:`sdar_tamp.compat.pddlstream.alias`) is installed first, so the program's
``import pddlstream...`` lines resolve here, even with a PDDLStream checkout on ``sys.path``
(its ``examples`` helper modules stay importable). The program runs as ``__main__``.
"""

from __future__ import annotations

import json
import logging
import os
import runpy
import sys
import time
from collections.abc import Sequence
from typing import Any

from sdar_tamp.compat.pddlstream.alias import install_alias

USAGE = (
    "usage: python -m sdar_tamp.compat.pddlstream [-v] [--report FILE] "
    "(PROGRAM.py | -m MODULE) [ARGS ...]\n"
    "Runs a PDDLStream program with 'import pddlstream' resolved to sdar_tamp's compatibility "
    "layer; -v shows the solver's log; --report FILE writes a JSON record of every solve call "
    "of the program, each plan re-checked by simulation (see sdar_tamp.compat.pddlstream.check)."
)


class _Recorder:
    """Wraps the solver entry points of this process to record and re-check each result.

    The record is written to ``path`` after every call (``"finished": false``) and once more
    when the program ends, so a program stopped from outside (a closed-loop program that plans
    again after each execution, killed at a time limit) still leaves the calls it made."""

    def __init__(self, path: str) -> None:
        self.path = path
        self.calls: list[dict[str, Any]] = []

    def install(self) -> None:
        from sdar_tamp.compat.pddlstream.algorithms import meta, search

        core_solve = getattr(meta, "core_solve")  # noqa: B009
        classical_plan = getattr(search, "plan")  # noqa: B009

        def recorded_solve(problem: Any, *args: Any, **kwargs: Any) -> Any:
            from sdar_tamp.compat.pddlstream.check import check_solution

            start, cpu = time.perf_counter(), time.process_time()
            solution = core_solve(problem, *args, **kwargs)
            seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
            error = check_solution(problem, solution) if solution.plan is not None else None
            self.calls.append(
                {
                    "entry": "solve",
                    "algorithm": kwargs.get("algorithm"),
                    "solved": solution.plan is not None,
                    "valid": solution.plan is not None and error is None,
                    "error": error,
                    "length": None if solution.plan is None else len(solution.plan),
                    "cost": solution.cost,
                    "seconds": round(seconds, 4),
                    "cpu_seconds": round(cpu, 4),  # the process's, its threads included
                }
            )
            self.write(None, finished=False)
            return solution

        def recorded_plan(task: Any, *args: Any, **kwargs: Any) -> Any:
            start = time.perf_counter()
            result = classical_plan(task, *args, **kwargs)
            self.calls.append(
                {
                    "entry": "solve_from_pddl",
                    "solved": result.plan is not None,
                    "valid": result.plan is not None,  # the planner validates its plans
                    "error": None,
                    "length": None if result.plan is None else len(result.plan),
                    "cost": result.cost,
                    "seconds": round(time.perf_counter() - start, 4),
                }
            )
            self.write(None, finished=False)
            return result

        setattr(meta, "core_solve", recorded_solve)  # noqa: B010
        setattr(search, "plan", recorded_plan)  # noqa: B010

    def write(self, failure: BaseException | None, finished: bool = True) -> None:
        """Write the record (whole or not at all: a new file replaces the old one)."""
        record = {
            "calls": self.calls,
            "exception": None if failure is None else f"{type(failure).__name__}: {failure}",
            "finished": finished,
        }
        partial = f"{self.path}.partial"
        with open(partial, "w", encoding="utf-8") as handle:
            json.dump(record, handle, default=str)
        os.replace(partial, self.path)


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    level = logging.WARNING
    if args and args[0] == "-v":
        level = logging.INFO
        args.pop(0)
    if not args or args[0] in ("-h", "--help"):
        print(USAGE)
        return 0 if args else 2
    report = None
    if args[0] == "--report" and len(args) > 1:
        report, args = args[1], args[2:]
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s")
    install_alias()
    if report is None:
        return _run(args)
    recorder = _Recorder(report)
    recorder.install()
    failure: BaseException | None = None
    try:
        return _run(args)
    except BaseException as error:  # recorded, then raised again
        failure = error
        raise
    finally:
        recorder.write(None if isinstance(failure, SystemExit) else failure)


def _run(args: list[str]) -> int:
    if not args:
        print(USAGE, file=sys.stderr)
        return 2
    if args[0] == "-m":
        if len(args) < 2:
            print(USAGE, file=sys.stderr)
            return 2
        module, rest = args[1], args[2:]
        sys.argv = [module, *rest]
        if "" not in sys.path:
            sys.path.insert(0, "")
        runpy.run_module(module, run_name="__main__", alter_sys=True)
        return 0
    path, rest = args[0], args[1:]
    sys.argv = [path, *rest]
    sys.path.insert(0, os.path.dirname(os.path.abspath(path)))  # as `python path` does
    runpy.run_path(path, run_name="__main__")
    return 0


if __name__ == "__main__":
    sys.exit(main())
