"""Fast Downward as an optional backend (``pip install sdar-tamp[fd]``).

The ``up-fast-downward`` wheel ships the planner (its Python driver and a compiled search
binary); it runs in a subprocess in a temporary folder, so nothing is written to the working
directory. Search and heuristic names are this package's (:data:`SEARCHES`,
:data:`~solvers.classical.heuristics.HEURISTICS`): ``lazy-gbfs`` with ``ff-lmcount`` is Fast
Downward's own ``lama-first``; the others map onto the matching Fast Downward configuration.
"""

from __future__ import annotations

import importlib.util
import math
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from sdar_tamp.errors import ParameterError
from solvers.classical.errors import BackendUnavailableError, PlanValidationError
from solvers.classical.numeric_task import plan_numeric
from solvers.classical.plan_check import validated_plan_cost
from solvers.classical.planner import ground_or_timeout
from solvers.classical.problem import (
    GroundAction,
    PlanningTask,
    PlanStatus,
    SearchResult,
    SearchStatistics,
)
from solvers.classical.sas import sas_task

_HEURISTICS = {
    "ff": "eval_modify_costs(ff(),cost_type=plusone)",
    "add": "eval_modify_costs(add(),cost_type=plusone)",
    "max": "hmax()",
    "blind": "blind()",
    "lmcount": "eval_modify_costs(landmark_sum(lm_factory=lm_rhw()),cost_type=plusone)",
}
_MISSING = "Fast Downward is not installed: pip install 'sdar-tamp[fd]' (up-fast-downward)"
#: Fast Downward's lama-first (its alias) as a search option, so that it can take a bound.
_LAMA_FIRST = (
    "let(hlm,eval_modify_costs(landmark_sum(lm_factory=lm_reasonable_orders_hps(lm_rhw()),"
    "pref=false),cost_type=one),let(hff,eval_modify_costs(ff(),cost_type=one),"
    "lazy_greedy([hff,hlm],preferred=[hff,hlm],cost_type=one,reopen_closed=false{options})))"
)


def fast_downward_script() -> Path | None:
    """The driver script of the installed ``up-fast-downward`` wheel, or None."""
    spec = importlib.util.find_spec("up_fast_downward")
    if spec is None or not spec.submodule_search_locations:
        return None
    script = Path(next(iter(spec.submodule_search_locations))) / "downward" / "fast-downward.py"
    return script if script.is_file() else None


def downward_binary() -> Path | None:
    """The search binary of the installed ``up-fast-downward`` wheel, or None."""
    script = fast_downward_script()
    if script is None:
        return None
    binary = script.parent / "builds" / "release" / "bin" / "downward"
    return binary if binary.is_file() else None


def require_fast_downward() -> Path:
    """The search binary; :class:`BackendUnavailableError` naming the extra when missing."""
    binary = downward_binary()
    if binary is None:
        raise BackendUnavailableError(_MISSING)
    return binary


def fast_downward_arguments(search: str, heuristic: str, weight: float = 2.0) -> list[str]:
    """The Fast Downward search options of a search and heuristic of this package."""
    if search == "lazy-gbfs" and heuristic == "ff-lmcount":
        return ["--alias", "lama-first"]
    return ["--search", search_engine(search, heuristic, weight)]


def search_engine(search: str, heuristic: str, weight: float = 2.0, options: str = "") -> str:
    """The Fast Downward search engine of a search and heuristic of this package; ``options``
    (e.g. ``",bound=10"``) are appended to the engine's arguments."""
    if search == "lazy-gbfs" and heuristic == "ff-lmcount":
        return _LAMA_FIRST.format(options=options)
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
        engine = f"eager_greedy([{hs}]{preferred}{options})"
    elif search == "lazy-gbfs":
        engine = f"lazy_greedy([{hs}]{preferred},cost_type=one,reopen_closed=false{options})"
    elif search == "wastar":
        if weight != int(weight):
            raise ParameterError(f"weight must be an integer for Fast Downward; got {weight!r}")
        engine = f"eager_wastar([{hs}]{preferred},w={weight:g}{options})"
    elif search == "lazy-wastar":
        if weight != int(weight):
            raise ParameterError(f"weight must be an integer for Fast Downward; got {weight!r}")
        engine = (
            f"lazy_wastar([{hs}]{preferred},reopen_closed=true,w={weight:g},"
            f"cost_type=plusone{options})"
        )
    elif search == "astar" and len(names) == 1:
        engine = f"astar({names[0]}{options})"
    else:
        raise ParameterError(
            f"search {search!r} with heuristic {heuristic!r} has no Fast Downward mapping"
        )
    for name, evaluator in reversed(list(zip(names, evaluators, strict=True))):
        engine = f"let({name},{evaluator},{engine})"
    return engine


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
        raise BackendUnavailableError(_MISSING)
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
        if run.returncode in (10, 11, 12, 13):
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


def plan_task_with_fast_downward(
    task: PlanningTask,
    *,
    search: str = "lazy-gbfs",
    heuristic: str = "ff-lmcount",
    weight: float = 2.0,
    time_limit: float | None = None,
    cost_bound: float = math.inf,
) -> SearchResult:
    """Plan for ``task`` with Fast Downward's search on this package's grounding.

    The task is grounded here (so everything :func:`~solvers.classical.plan` accepts works,
    ``extra_cost`` and numeric cost terms included), written in SAS+ (:mod:`.sas`) and searched
    by Fast Downward's binary in a subprocess; the plan is checked and costed by this package's
    validator. ``time_limit`` [s] covers grounding and search; ``cost_bound`` keeps only plans
    cheaper than it, as in :func:`~solvers.classical.plan`.

    Raises:
        BackendUnavailableError: ``up-fast-downward`` is not installed, or its search failed.
        ParameterError: a search/heuristic pair without a Fast Downward configuration.
    """
    binary = require_fast_downward()
    if time_limit is not None and not time_limit > 0:
        raise ParameterError(f"time_limit must be > 0 seconds or None; got {time_limit!r}")
    search_engine(search, heuristic, weight)  # an unknown pair fails before grounding
    if time_limit is not None and math.isinf(time_limit):
        time_limit = None
    if task.domain.numeric:  # numeric fluents: compiled away for their reachable values
        return plan_numeric(
            task,
            lambda t: plan_task_with_fast_downward(
                t,
                search=search,
                heuristic=heuristic,
                weight=weight,
                time_limit=time_limit,
                cost_bound=cost_bound,
            ),
        )
    start = time.perf_counter()
    deadline = None if time_limit is None else start + time_limit
    ground_task = ground_or_timeout(task, start, deadline)
    if isinstance(ground_task, SearchResult):
        return ground_task
    grounded = time.perf_counter()

    def statistics(log: str = "") -> SearchStatistics:
        return SearchStatistics(
            expanded=_last_int(r"Expanded (\d+) state", log),
            generated=_last_int(r"Generated (\d+) state", log),
            evaluated=_last_int(r"Evaluations: (\d+)", log),
            ground_actions=len(ground_task.operators),
            ground_axioms=len(ground_task.axioms),
            reachable_facts=len(ground_task.facts),
            grounding_time=grounded - start,
            search_time=time.perf_counter() - grounded,
        )

    if not ground_task.goal_reachable:
        return SearchResult(PlanStatus.UNSOLVABLE, None, 0.0, statistics())
    if not ground_task.goal and not ground_task.negative_goal:
        return SearchResult(PlanStatus.SOLVED, (), 0.0, statistics())
    sas = sas_task(ground_task)
    options = ""
    bound = sas.scaled_bound(cost_bound)
    if bound is not None:
        options += f",bound={bound}"
    remaining = None if deadline is None else deadline - time.perf_counter()
    if remaining is not None:
        if remaining <= 0:
            return SearchResult(PlanStatus.TIMEOUT, None, 0.0, statistics())
        options += f",max_time={remaining:.3f}"
    engine = search_engine(search, heuristic, weight, options)
    with tempfile.TemporaryDirectory(prefix="sdar-fd-") as folder:
        work = Path(folder)
        command = [str(binary), "--search", engine, "--internal-plan-file", str(work / "plan")]
        try:
            run = subprocess.run(
                command,
                input=sas.text,
                cwd=work,
                capture_output=True,
                text=True,
                check=False,
                # the search stops itself at max_time; this only catches a stuck process
                timeout=None if remaining is None else remaining + 5.0,
            )
        except subprocess.TimeoutExpired:
            return SearchResult(PlanStatus.TIMEOUT, None, 0.0, statistics())
        plan_path = work / "plan"
        plan_text = plan_path.read_text() if plan_path.is_file() else None
    if plan_text is None:
        # exit codes: 11 unsolvable, 12 unsolved by an incomplete search, 13 unsolvable
        # within the bound; 22-24 out of memory or time
        if run.returncode in (11, 12, 13):
            return SearchResult(PlanStatus.UNSOLVABLE, None, 0.0, statistics(run.stdout))
        if run.returncode in (22, 23, 24):
            return SearchResult(PlanStatus.TIMEOUT, None, 0.0, statistics(run.stdout))
        raise BackendUnavailableError(
            f"Fast Downward failed (exit {run.returncode}): "
            f"{(run.stderr or run.stdout).strip()[-500:]}"
        )
    indices = [int(step.name[1:]) for step in parse_plan(plan_text)[0]]
    steps = tuple(ground_task.operators[i].action for i in indices)
    try:
        cost = validated_plan_cost(task, steps)
    except PlanValidationError as error:
        raise BackendUnavailableError(f"Fast Downward returned an invalid plan: {error}") from error
    if cost >= cost_bound:  # costs finer than the SAS+ scale were rounded
        return SearchResult(PlanStatus.UNSOLVABLE, None, 0.0, statistics(run.stdout))
    return SearchResult(PlanStatus.SOLVED, steps, cost, statistics(run.stdout))


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
