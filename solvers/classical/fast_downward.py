"""Fast Downward as an optional backend (``pip install sdar-tamp[fd]``).

The ``up-fast-downward`` wheel ships the planner (its Python driver and a compiled search
binary); it runs in a subprocess in a temporary folder, so nothing is written to the working
directory. Search and heuristic names are this package's (:data:`SEARCHES`,
:data:`~solvers.classical.heuristics.HEURISTICS`): ``lazy-gbfs`` with ``ff-lmcount`` is Fast
Downward's own ``lama-first``; the others map onto the matching Fast Downward configuration.
"""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from sdar_tamp.errors import ParameterError
from solvers.classical.errors import BackendUnavailableError
from solvers.classical.problem import GroundAction, PlanStatus, SearchResult, SearchStatistics

_HEURISTICS = {
    "ff": "eval_modify_costs(ff(),cost_type=plusone)",
    "add": "eval_modify_costs(add(),cost_type=plusone)",
    "max": "hmax()",
    "blind": "blind()",
    "lmcount": "eval_modify_costs(landmark_sum(lm_factory=lm_rhw()),cost_type=plusone)",
}


def fast_downward_script() -> Path | None:
    """The driver script of the installed ``up-fast-downward`` wheel, or None."""
    spec = importlib.util.find_spec("up_fast_downward")
    if spec is None or not spec.submodule_search_locations:
        return None
    script = Path(next(iter(spec.submodule_search_locations))) / "downward" / "fast-downward.py"
    return script if script.is_file() else None


def fast_downward_arguments(search: str, heuristic: str, weight: float = 2.0) -> list[str]:
    """The Fast Downward search options of a search and heuristic of this package."""
    if search == "lazy-gbfs" and heuristic == "ff-lmcount":
        return ["--alias", "lama-first"]
    if heuristic == "ff-lmcount":
        evaluators = [_HEURISTICS["ff"], _HEURISTICS["lmcount"]]
    elif heuristic in _HEURISTICS:
        evaluators = [_HEURISTICS[heuristic]]
    else:
        raise ParameterError(
            f"heuristic must be one of {', '.join((*_HEURISTICS, 'ff-lmcount'))}; got {heuristic!r}"
        )
    names = [f"h{i}" for i in range(len(evaluators))]
    hs = ",".join(names)
    preferred = "" if heuristic in ("blind", "lmcount", "max") else f",preferred=[{names[0]}]"
    if search == "gbfs":
        engine = f"eager_greedy([{hs}]{preferred})"
    elif search == "lazy-gbfs":
        engine = f"lazy_greedy([{hs}]{preferred},cost_type=one,reopen_closed=false)"
    elif search == "wastar":
        engine = f"eager_wastar([{hs}]{preferred},w={weight:g})"
    elif search == "astar" and len(names) == 1:
        engine = f"astar({names[0]})"
    else:
        raise ParameterError(
            f"search {search!r} with heuristic {heuristic!r} has no Fast Downward mapping"
        )
    for name, evaluator in reversed(list(zip(names, evaluators, strict=True))):
        engine = f"let({name},{evaluator},{engine})"
    return ["--search", engine]


def plan_with_fast_downward(
    domain_file: Path,
    problem_file: Path,
    *,
    search: str = "lazy-gbfs",
    heuristic: str = "ff-lmcount",
    weight: float = 2.0,
    time_limit: float | None = None,
) -> SearchResult:
    """Run Fast Downward on PDDL files; ``time_limit`` [s] is its overall limit.

    Raises:
        BackendUnavailableError: ``up-fast-downward`` is not installed.
        ParameterError: a search/heuristic pair without a Fast Downward configuration.
    """
    script = fast_downward_script()
    if script is None:
        raise BackendUnavailableError(
            "Fast Downward is not installed: pip install 'sdar-tamp[fd]' (up-fast-downward)"
        )
    if time_limit is not None and not time_limit > 0:
        raise ParameterError(f"time_limit must be > 0 seconds or None; got {time_limit!r}")
    search_options = fast_downward_arguments(search, heuristic, weight)
    with tempfile.TemporaryDirectory(prefix="sdar-fd-") as folder:
        work = Path(folder)
        command = [sys.executable, str(script), "--plan-file", str(work / "plan")]
        command += ["--sas-file", str(work / "output.sas")]
        if time_limit is not None:
            command += ["--overall-time-limit", f"{max(1, round(time_limit))}s"]
        alias = search_options[:2] if search_options[0] == "--alias" else []
        command += [*alias, str(domain_file.resolve()), str(problem_file.resolve())]
        command += search_options[len(alias) :]
        start = time.perf_counter()
        run = subprocess.run(command, cwd=work, capture_output=True, text=True, check=False)
        elapsed = time.perf_counter() - start
        plan_path = work / "plan"
        plan_text = plan_path.read_text() if plan_path.is_file() else None
    log = run.stdout
    expanded = _last_int(r"Expanded (\d+) state", log)
    statistics = SearchStatistics(
        expanded=expanded,
        generated=_last_int(r"Generated (\d+) state", log),
        evaluated=_last_int(r"Evaluations: (\d+)", log),
        ground_actions=0,
        ground_axioms=0,
        reachable_facts=0,
        grounding_time=_last_float(r"Done! \[([\d.]+)s CPU", log),
        search_time=_last_float(r"Search time: ([\d.]+)s", log),
    )
    if plan_text is None:
        # exit codes of the driver: 11/12 unsolvable, 23/24 out of time (or memory)
        if run.returncode in (10, 11, 12):
            status = PlanStatus.UNSOLVABLE
        elif run.returncode in (21, 22, 23, 24):
            status = PlanStatus.TIMEOUT
        else:
            raise BackendUnavailableError(
                f"Fast Downward failed (exit {run.returncode}) after {elapsed:.1f} s: "
                f"{(run.stderr or log).strip()[-500:]}"
            )
        return SearchResult(status, None, 0.0, statistics)
    steps, cost = parse_plan(plan_text)
    return SearchResult(PlanStatus.SOLVED, steps, cost, statistics)


def parse_plan(text: str) -> tuple[tuple[GroundAction, ...], float]:
    """Steps and cost of a plan file: ``(name arg ...)`` lines, ``; cost = N`` comment."""
    steps: list[GroundAction] = []
    cost = None
    for line in text.splitlines():
        line = line.strip()
        if line.startswith("("):
            name, *args = line.strip("()").split()
            steps.append(GroundAction(name, tuple(args)))
        elif match := re.match(r";\s*cost\s*=\s*([\d.]+)", line):
            cost = float(match.group(1))
    return tuple(steps), float(len(steps)) if cost is None else cost


def _last_int(pattern: str, text: str) -> int:
    found = re.findall(pattern, text)
    return int(found[-1]) if found else 0


def _last_float(pattern: str, text: str) -> float:
    found = re.findall(pattern, text)
    return float(found[-1]) if found else 0.0
