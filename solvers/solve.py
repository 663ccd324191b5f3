"""``solve(problem, algorithm=..., **options)``: PDDLStream's entry point and arguments."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import logging
import math
import random
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from sdar_tamp.arguments import (
    COST_BOUND,
    COUNT,
    MAX_TIME,
    SEED,
    TIME_LIMIT,
    Integer,
    Real,
    optional,
)
from sdar_tamp.errors import ParameterError
from sdar_tamp.language.options import FunctionInfo, PlanConstraints, StreamInfo
from sdar_tamp.language.problem import PDDLProblem
from sdar_tamp.logs import get_logger
from solvers.classical import HEURISTICS, SEARCHES
from solvers.solution import Solution, print_solution
from solvers.stream_planning.constraints import compile_constraints
from solvers.stream_planning.options import StreamOptions
from solvers.stream_planning.policies import ALGORITHMS
from solvers.stream_planning.solver import StreamSolver

if TYPE_CHECKING:
    from solvers.sdar.options import SdarOptions
    from solvers.sdar.solver import SdarSolver

LOG = get_logger(__name__)
INF = math.inf
_LIMIT = Real(0.0, allow_inf=True)  # max_iterations, max_skeletons, search_sample_ratio
_NATURAL = Integer(0)  # initial_complexity
_WEIGHT = Real(0.0, closed=True)  # effort_weight

#: PDDLStream's Fast Downward configurations -> (search, heuristic, weight) of the classical
#: planner. Names whose heuristic is not available use the nearest one (noted in the log).
PLANNER_ALIASES: dict[str, tuple[str, str, float]] = {
    "dijkstra": ("astar", "blind", 1.0),
    "max-astar": ("astar", "max", 1.0),
    "lmcut-astar": ("astar", "max", 1.0),
    "ff-astar": ("astar", "ff", 1.0),
    "ff-eager": ("gbfs", "ff", 1.0),
    "ff-eager-pref": ("gbfs", "ff", 1.0),
    "ff-lazy": ("gbfs", "ff", 1.0),
    "goal-lazy": ("gbfs", "ff", 1.0),
    "add-random-lazy": ("gbfs", "add", 1.0),
    "ff-eager-tiebreak": ("gbfs", "ff", 1.0),
    "ff-lazy-tiebreak": ("gbfs", "ff", 1.0),
    "ff-ehc": ("gbfs", "ff", 1.0),
    # Fast Downward's lazy_wastar with preferred operators, as PDDLStream configures them
    **{f"ff-wastar{w}": ("lazy-wastar", "ff", float(w)) for w in range(1, 6)},
    **{f"cea-wastar{w}": ("lazy-wastar", "ff", float(w)) for w in range(1, 6)},
    **{f"ff-astar{w}": ("wastar", "ff", float(w)) for w in range(1, 6)},
}
_APPROXIMATED = {
    "lmcut-astar": "h^lmcut is not available; A* with the admissible h^max",
    "goal-lazy": "the goal-count heuristic is not available; greedy search with h^FF",
    "cea-wastar": "h^cea is not available; weighted A* with h^FF",
}


#: The prefix of ``planner`` names that run Fast Downward (``"fd"`` alone: its default search).
FD_PREFIX = "fd:"


def parse_planner_choice(planner: str) -> tuple[str, str, str, float]:
    """``(backend, search, heuristic, weight)`` of a ``solve(planner=...)`` value: a name of
    :func:`parse_planner` (this package's planner, backend ``"sdar"``), or the same name after
    ``fd:`` (Fast Downward, backend ``"fd"``, e.g. ``fd:wastar-ff``, ``fd:lazy-gbfs-ff-lmcount``,
    ``fd:ff-astar``); ``fd`` alone is Fast Downward with the default ``wastar-ff``.

    Raises:
        ParameterError: an unknown name, or one without a Fast Downward configuration.
        BackendUnavailableError: ``fd`` asked for and ``up-fast-downward`` not installed (the
            message names the ``sdar-tamp[fd]`` extra).
    """
    name = str(planner)
    if name.lower() != "fd" and not name.lower().startswith(FD_PREFIX):
        return ("sdar", *parse_planner(name))
    from solvers.classical.fast_downward import require_fast_downward, search_engine

    search, heuristic, weight = parse_planner(name[len(FD_PREFIX) :] or "wastar-ff")
    search_engine(search, heuristic, weight)
    require_fast_downward()
    return "fd", search, heuristic, weight


def parse_planner(planner: str) -> tuple[str, str, float]:
    """``(search, heuristic, weight)`` of a planner name: ``SEARCH-HEURISTIC`` (e.g.
    ``wastar-ff``, ``gbfs-add``, ``astar-max``) or one of PDDLStream's names
    (:data:`PLANNER_ALIASES`, e.g. ``ff-astar``, ``max-astar``, ``ff-wastar3``).

    Raises:
        ParameterError: an unknown name; the message lists the valid ones.
    """
    name = str(planner).lower()
    if name in PLANNER_ALIASES:
        for prefix, note in _APPROXIMATED.items():
            if name.startswith(prefix):
                LOG.info("planner %r: %s", planner, note)
        return PLANNER_ALIASES[name]
    # the longest search name that prefixes it ("lazy-gbfs-ff" is lazy-gbfs with h_FF)
    for search in sorted(SEARCHES, key=len, reverse=True):
        if name == search or name.startswith(search + "-"):
            heuristic = name[len(search) + 1 :] or "ff"
            if heuristic in HEURISTICS:
                return search, heuristic, 2.0
            break
    native = [f"{s}-{h}" for s in SEARCHES for h in HEURISTICS]
    raise ParameterError(
        f"planner must be SEARCH-HEURISTIC ({', '.join(native)}) or one of PDDLStream's "
        f"{', '.join(sorted(PLANNER_ALIASES))}; got {planner!r}"
    )


def solve(
    problem: PDDLProblem,
    algorithm: str = "adaptive",
    stream_info: Mapping[str, StreamInfo | FunctionInfo] | None = None,
    constraints: PlanConstraints | None = None,
    unit_costs: bool = False,
    success_cost: float = INF,
    max_time: float = INF,
    max_iterations: float = INF,
    max_skeletons: float = INF,
    search_sample_ratio: float = 1.0,
    initial_complexity: int = 0,
    complexity_step: int = 1,
    max_complexity: float = INF,
    unit_efforts: bool = False,
    effort_weight: float | None = None,
    max_planner_time: float = INF,
    enforce_max_time: bool = True,
    verbose: bool = True,
    seed: int | None = None,
    planner: str = "wastar-ff",
    task_planner: str | None = None,
    sdar_options: SdarOptions | None = None,
    **unknown: Any,
) -> Solution:
    """Solve ``problem``; returns a :class:`Solution` (``plan, cost, certificate = solution``).

    Args:
        algorithm: one of ``incremental``, ``focused``, ``binding``, ``adaptive`` or ``sdar``
            (rearrangement domains: dependency-driven steps grounded best first, see
            :mod:`solvers.sdar.solver`).
        stream_info: per-stream :class:`StreamInfo` / :class:`FunctionInfo`, by stream name.
        constraints: :class:`PlanConstraints`: plan skeletons (values, ``WILD``, ``"?x"``
            variables; ``exact``) and ``max_cost`` (see
            :mod:`solvers.stream_planning.constraints`).
        unit_costs: every action costs 1 instead of its ``total-cost`` increase.
        effort_weight: when set, each optimistic action costs, for the planner, this weight
            times the effort of the stream results behind its preconditions more
            (``StreamInfo.effort``, or ``overhead / p_success``; 1 per call with
            ``unit_efforts``), and queued optimistic plans are tried in the order of cost
            plus weighted effort.
        success_cost: stop at the first plan of at most this cost (else keep improving until
            ``max_time``).
        max_time: wall-clock limit [s].
        enforce_max_time: (stream algorithms, finite ``max_time``) run user samplers, tests and
            functions one at a time in a worker thread, so that one that blocks cannot hold
            the solve past ``max_time``: the call is abandoned (it finishes in the
            background), a warning names it and the solve returns ``TIMEOUT``. With False they
            run in the calling thread (for code tied to it) and the deadline is checked after
            each call, so a blocking call delays the ``TIMEOUT`` until it returns.
        planner: ``SEARCH-HEURISTIC`` of the classical planner, e.g. ``wastar-ff``,
            ``gbfs-ff``, ``astar-max``, or a PDDLStream planner name such as ``ff-astar``,
            ``max-astar`` or ``ff-wastar2`` (see :func:`parse_planner`). With the prefix
            ``fd:`` (``fd:wastar-ff``, ``fd:ff-astar``; ``fd`` alone for ``fd:wastar-ff``)
            Fast Downward's search runs the same configuration on this package's grounding
            (``pip install 'sdar-tamp[fd]'``; see :func:`parse_planner_choice`).
        task_planner: with ``algorithm="sdar"``: ``sdar`` (SDAR-T) or ``baseline``
            (default: the problem's ``solve_defaults``, else ``sdar``).
        sdar_options: with ``algorithm="sdar"``: SDAR-M's budgets and switches
            (:class:`solvers.sdar.options.SdarOptions`; its ``max_time`` is replaced by
            ``max_time``; default: the problem's ``solve_defaults``, else the defaults). A
            rearrangement built by :mod:`sdar_tamp.app` carries its ``PlannerConfig``'s
            task planner and options in ``solve_defaults``, so ``solve(r.problem,
            algorithm="sdar")`` plans as ``solve_rearrangement(r)`` does.
        seed: Python's ``random`` and NumPy's global generator are seeded with it for the
            duration of the solve, so samplers that draw from them (as PDDLStream programs'
            samplers do) give the same plan for the same seed; their previous states are
            restored when ``solve`` returns. The solvers draw no random numbers themselves.
        verbose: log a one-line summary of the result at INFO on the ``sdar_tamp.solvers``
            logger (else at DEBUG). Logger levels and handlers are the application's:
            ``solve`` never changes them. With the stream algorithms, also print one line per
            round (level, outcome, stream calls and new facts, time) and the final counts
            (per stream, and why no plan was found) on standard output
            (:mod:`solvers.stream_planning.progress`).

    Every numeric argument is checked (with ``algorithm="sdar"`` too) by the rules of
    :mod:`sdar_tamp.arguments`: NaN is refused everywhere; ``inf`` means "no limit" for the
    budgets and bounds; ``seed``, ``initial_complexity`` are integers >= 0 and
    ``complexity_step`` an integer >= 1.

    Raises:
        ParameterError: an argument out of range or unknown; the message names it.
        StreamError: a user sampler raised (chained) or returned the wrong shape.
    """
    if unknown:
        raise ParameterError(f"unknown solve() argument(s): {', '.join(sorted(unknown))}")
    if algorithm not in (*ALGORITHMS, "sdar"):
        raise ParameterError(
            f"algorithm must be one of {', '.join((*ALGORITHMS, 'sdar'))}; got {algorithm!r}"
        )
    if not isinstance(problem, PDDLProblem):
        raise ParameterError(f"problem must be a PDDLProblem, got {type(problem).__name__}")
    max_time = MAX_TIME.check("max_time", max_time)
    success_cost = COST_BOUND.check("success_cost", success_cost)
    max_complexity = COST_BOUND.check("max_complexity", max_complexity)
    initial_complexity = _NATURAL.check("initial_complexity", initial_complexity)
    complexity_step = COUNT.check("complexity_step", complexity_step)
    effort_weight = optional(_WEIGHT, "effort_weight", effort_weight)
    seed = None if seed is None else SEED.check("seed", seed)
    max_iterations = _LIMIT.check("max_iterations", max_iterations)
    max_skeletons = _LIMIT.check("max_skeletons", max_skeletons)
    search_sample_ratio = _LIMIT.check("search_sample_ratio", search_sample_ratio)
    max_planner_time = MAX_TIME.check("max_planner_time", max_planner_time)
    if algorithm == "sdar":
        task_planner, sdar_options = _sdar_defaults(problem, task_planner, sdar_options)
        with _seeded_globals(seed):
            return _solve_sdar(problem, task_planner, max_time, stream_info, verbose, sdar_options)
    if sdar_options is not None:
        raise ParameterError(f"sdar_options applies to algorithm 'sdar' only, not {algorithm!r}")
    backend, search, heuristic, weight = parse_planner_choice(planner)
    options = StreamOptions(
        algorithm=algorithm,
        unit_costs=unit_costs,
        success_cost=success_cost,
        max_time=max_time,
        max_iterations=max_iterations,
        max_skeletons=max_skeletons,
        search_sample_ratio=search_sample_ratio,
        initial_complexity=initial_complexity,
        complexity_step=complexity_step,
        max_complexity=max_complexity,
        max_planner_time=max_planner_time,
        search=search,
        heuristic=heuristic,
        weight=weight,
        backend=backend,
    )
    if constraints is not None and not isinstance(constraints, PlanConstraints):
        raise ParameterError(
            f"constraints must be a PlanConstraints, got {type(constraints).__name__}"
        )
    options = dataclasses.replace(
        options,
        effort_weight=effort_weight,
        unit_efforts=bool(unit_efforts),
        enforce_max_time=bool(enforce_max_time),
        verbose=bool(verbose),
    )
    if constraints is not None:
        options = dataclasses.replace(options, max_cost=constraints.max_cost)
        problem = compile_constraints(problem, constraints)
    with _seeded_globals(seed):
        solution = StreamSolver(problem, options, stream_info).solve()
    return _summarised(solution, algorithm, verbose)


@contextlib.contextmanager
def _seeded_globals(seed: int | None) -> Iterator[None]:
    """Seed ``random`` and NumPy's global generator with ``seed`` inside the block and restore
    their states after it (nothing happens for ``seed=None``)."""
    if seed is None:
        yield
        return
    import numpy

    saved = random.getstate(), numpy.random.get_state()
    random.seed(seed)
    numpy.random.seed(seed % 2**32)
    try:
        yield
    finally:
        random.setstate(saved[0])
        numpy.random.set_state(saved[1])


def _summarised(solution: Solution, algorithm: str, verbose: bool) -> Solution:
    """``solution``, after logging its one-line summary (INFO if ``verbose``, else DEBUG)."""
    LOG.log(
        logging.INFO if verbose else logging.DEBUG,
        "%s: %s, cost %s, %d action(s), %.3f s",
        algorithm,
        solution.status.value,
        f"{solution.cost:g}",
        len(solution.plan or ()),
        float(solution.statistics.get("time", solution.statistics.get("planning_time", 0.0))),
    )
    return solution


#: The keywords of ``solve()`` a problem's ``solve_defaults`` may carry.
SOLVE_DEFAULTS = ("task_planner", "sdar_options")


def _sdar_defaults(
    problem: PDDLProblem, task_planner: str | None, sdar_options: SdarOptions | None
) -> tuple[str, SdarOptions | None]:
    """The task planner and SDAR-M options: the arguments, else the problem's defaults."""
    defaults = getattr(problem, "solve_defaults", None) or {}
    if not isinstance(defaults, Mapping):
        raise ParameterError(
            f"PDDLProblem.solve_defaults must be a mapping, got {type(defaults).__name__}"
        )
    unknown = sorted(set(defaults) - set(SOLVE_DEFAULTS))
    if unknown:
        raise ParameterError(
            f"PDDLProblem.solve_defaults may hold {', '.join(SOLVE_DEFAULTS)}; "
            f"got {', '.join(map(repr, unknown))}"
        )
    if task_planner is None:
        task_planner = defaults.get("task_planner", "sdar")
    if sdar_options is None:
        sdar_options = defaults.get("sdar_options")
    return str(task_planner), sdar_options


def _solve_sdar(
    problem: PDDLProblem,
    task_planner: str,
    max_time: float,
    stream_info: Mapping[str, StreamInfo | FunctionInfo] | None,
    verbose: bool,
    sdar_options: SdarOptions | None,
) -> Solution:
    solver = sdar_solver(problem, task_planner, max_time, stream_info, sdar_options)
    return _summarised(solver.solve(), "sdar", verbose)


def sdar_solver(
    problem: PDDLProblem,
    task_planner: str | None = None,
    max_time: float = INF,
    stream_info: Mapping[str, StreamInfo | FunctionInfo] | None = None,
    sdar_options: SdarOptions | None = None,
) -> SdarSolver:
    """The SDAR solver that ``solve(problem, algorithm="sdar", ...)`` runs, built alike (the
    problem's ``solve_defaults`` for what is not given), for a caller that takes its steps
    one at a time (:meth:`~solvers.sdar.solver.SdarSolver.steps`).

    Raises:
        ParameterError: ``max_time`` out of range, an unknown task planner, or
            ``sdar_options`` that is not a :class:`~solvers.sdar.options.SdarOptions`.
    """
    from solvers.sdar.options import SdarOptions
    from solvers.sdar.planners import make_task_planner
    from solvers.sdar.solver import SdarSolver

    max_time = MAX_TIME.check("max_time", max_time)
    name, sdar_options = _sdar_defaults(problem, task_planner, sdar_options)
    planner = make_task_planner(name)
    if sdar_options is not None and not isinstance(sdar_options, SdarOptions):
        raise ParameterError(
            f"sdar_options must be a SdarOptions, got {type(sdar_options).__name__}"
        )
    options = dataclasses.replace(sdar_options or SdarOptions(), max_time=max_time)
    return SdarSolver(problem, planner, options, stream_info)


def create_parser(default_algorithm: str = "adaptive") -> argparse.ArgumentParser:
    """PDDLStream's example parser: ``-a/--algorithm`` and ``-u/--unit``."""
    parser = argparse.ArgumentParser()
    parser.add_argument(
        "-a",
        "--algorithm",
        default=default_algorithm,
        choices=ALGORITHMS,
        help="stream planning algorithm (default: %(default)s)",
    )
    parser.add_argument("-u", "--unit", action="store_true", help="use unit action costs")
    return parser


def solve_from_command_line(
    make_problem: Callable[..., PDDLProblem],
    argv: Sequence[str] | None = None,
    default_max_time: float = 30.0,
) -> Solution:
    """An example's ``main``: parse ``-a/-u/--seed/--max-time``, build the problem with
    ``make_problem(seed=...)``, solve it and print the solution (returned for tests)."""
    parser = create_parser()
    parser.add_argument("--seed", type=SEED.parse, default=0, help="sampler seed (default: 0)")
    parser.add_argument(
        "--max-time",
        type=TIME_LIMIT.parse,
        default=default_max_time,
        help="[s] (default: %(default)s)",
    )
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    solution = solve(
        make_problem(seed=args.seed),
        algorithm=args.algorithm,
        unit_costs=args.unit,
        max_time=args.max_time,
        seed=args.seed,
        verbose=False,
    )
    print_solution(solution)
    return solution
