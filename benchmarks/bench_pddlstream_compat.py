"""PDDLStream's own examples, unmodified, on the compatibility layer.

Usage::

    python benchmarks/bench_pddlstream_compat.py PATH_TO_PDDLSTREAM_CHECKOUT [--timeout S]
                                                  [--only NAME ...] [--repeat N]
    PDDLSTREAM_PATH=... python benchmarks/bench_pddlstream_compat.py

Each example runs in its own subprocess, exactly as PDDLStream's README runs it
(``python -m examples.<folder>.run`` from the checkout's root), but started through
``python -m sdar_tamp.compat.pddlstream --report FILE -m examples.<...>``: the alias makes the
program's ``import pddlstream...`` lines resolve to ``sdar_tamp.compat.pddlstream`` (the
checkout's own ``pddlstream`` package is never imported; the runner fails the example if it
is), and every plan the program obtains is re-checked by simulation
(:mod:`sdar_tamp.compat.pddlstream.check`). An example passes when it found at least one plan
and every plan it found is valid; an error raised after a valid plan was found is reported but
does not fail the example, nor does the runner's time limit ending a program that plans again
after executing each plan (pr2_belief) once it has found a plan (the record is written after
every solve call).

The runner fixes the environment, never the examples: without a display (no ``$DISPLAY``) the
examples' tkinter viewers get a do-nothing stand-in and the pybullet ones connect in DIRECT mode
(their ``connect`` falls back to it by itself); every prompt is answered with Enter; NumPy
names removed in NumPy 2 that the examples use (``np.product``, ``np.mat``, ``np.math``) are
put back; ``discrete_belief`` and
``table_belief`` need SciPy (their own dependency: ``pip install scipy``, or a folder on
``PYTHONPATH``, which is passed on).

Your own PDDLStream program runs the same way::

    python -m sdar_tamp.compat.pddlstream my_program.py [its args]
    python -m sdar_tamp.compat.pddlstream -m my_package.my_module [its args]

or add ``import sdar_tamp.compat.pddlstream.install`` as its first import.

Three examples find no plan in PDDLStream itself either (run locally with Fast Downward, as
written): ``continuous_tamp_unfactored`` (not within its own 30 s), ``continuous_tamp_ffrob``
(unsolvable as written) and ``discrete_belief`` (its own ``opt_gen_fn`` raises); nor, among
the pybullet ones (run here with Fast Downward built from the checkout's caelan/downward
commit), ``tamp`` (no plan within its 120 s), ``pr2`` (its own cost function raises) and
``turtlebots`` (it needs Temporal Fast Downward, and its own collision predicate raises a
``TypeError`` on Python 3); the table says so under their rows, and the summary lists them as
``fail_in_pddlstream_too``.

Each example runs within its own time limit (the ``max_time`` it passes to ``solve``) plus
60 s for loading its world and re-checking its plans; one with no limit of its own (kuka, pr2,
pr2_belief) gets ``--unlimited`` (600 s), and one that states none 120 s; ``--timeout``
replaces all three.

Prints a table example -> result -> time [s]; the last line is one JSON object. Without a
checkout it prints ``{"skipped": "<why>", ...}`` as its last line and exits 0.

``--quick`` changes only the defaults: the ``blocksworld`` example alone, within 60 s (seconds
with a checkout; without one, the skip line). The JSON keys are the same, plus
``"quick": true``::

    python benchmarks/bench_pddlstream_compat.py PATH_TO_PDDLSTREAM_CHECKOUT --quick
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: [s] the runner's limit for an example that states none
DEFAULT_TIMEOUT = 120.0

#: what PDDLStream itself did with these examples, run here (Fast Downward built from the
#: checkout's own caelan/downward commit; docs/pddlstream.md has the figures)
TURTLEBOTS_UPSTREAM = (
    "stops at parsing: its durative actions go to Temporal Fast Downward, and without TFD_PATH "
    "(not here) parse_temporal_domain raises RuntimeError; its own collision predicate would "
    "then raise a TypeError on Python 3 (get_turtle_traj_aabb passes a map to aabb_union)"
)
TAMP_UPSTREAM = (
    "no plan within its own max_time=120 s either (137.7 s, 111 s of it in Fast Downward's "
    "searches; load 15-19)"
)
PR2_UPSTREAM = (
    "stops on an AttributeError in the example's own opt_move_cost_fn ('UniqueOptValue' object "
    "has no attribute 'values'), after 1.6 s"
)


@dataclass(frozen=True)
class Example:
    name: str
    module: str
    args: tuple[str, ...] = ()
    #: set when PDDLStream itself finds no plan for the example as written (run locally with
    #: Fast Downward, or, for turtlebots, read from its source): what happens there
    upstream: str = ""
    #: a module the example needs that is not a dependency of this project (an optional extra)
    needs: str = ""
    #: the example's own time limit [s] (the ``max_time`` it passes to ``solve``; ``math.inf``:
    #: it passes none); None: the runner's ``--timeout`` applies
    limit: float | None = None


EXAMPLES = (
    Example("blocksworld", "examples.blocksworld.run"),
    Example("blocksworld_derived", "examples.blocksworld.run_derived"),
    Example("kitchen", "examples.kitchen.run"),
    Example("discrete_tamp", "examples.discrete_tamp.run"),
    Example("discrete_tamp_push", "examples.discrete_tamp.push.run"),
    Example("continuous_tamp", "examples.continuous_tamp.run"),
    Example(
        "continuous_tamp_unfactored",
        "examples.continuous_tamp.unfactored.run",
        upstream="no plan within the example's own max_time=30 s (it is still sampling "
        "complexity 7: the same facts per level as here)",
    ),
    Example("continuous_tamp_rmmp", "examples.continuous_tamp.rmmp.run"),
    Example(
        "continuous_tamp_ffrob",
        "examples.continuous_tamp.ffrob.run",
        upstream="no plan: no (Grasp ?b ?g) fact in its initial state and no stream "
        "certifies one, so s-ik, Kin and pick never apply",
    ),
    Example("continuous_tamp_idtmp", "examples.continuous_tamp.idtmp.run"),
    Example("motion", "examples.motion.run"),
    Example(
        "discrete_belief",
        "examples.discrete_belief.run",
        upstream="stops on the same AssertionError: its opt_gen_fn for prob-after-move "
        "builds a degenerate distribution on a move to the same location",
    ),
    Example("table_belief", "examples.table_belief.run"),
    Example("adl", "examples.advanced.adl.run"),
    Example("adl_goal", "examples.advanced.adl.run_goal"),
    Example("counting", "examples.advanced.counting.run"),
    Example("defer", "examples.advanced.defer.run"),
    Example("exogenous", "examples.advanced.exogenous.run"),
    Example("fluent", "examples.advanced.fluent.run"),
    Example("wild", "examples.advanced.wild.run"),
    Example("multi_cost", "examples.advanced.multi_cost"),
    Example("storage", "examples.advanced.storage"),
    Example("satisfy", "examples.advanced.satisfy.run"),
    Example("rovers", "examples.ipc.rovers.run"),
    Example("satellites", "examples.ipc.satellites.run"),
    # the robot programs: PyBullet (``pip install sdar-tamp[pybullet]``) in DIRECT mode (no
    # $DISPLAY, so their ``connect`` opens no window)
    Example("kuka", "examples.pybullet.kuka.run", needs="pybullet", limit=math.inf),
    Example(
        "pr2",
        "examples.pybullet.pr2.run",
        needs="pybullet",
        limit=math.inf,
        upstream=PR2_UPSTREAM,
    ),
    Example("namo", "examples.pybullet.namo.run", needs="pybullet", limit=120.0),
    Example("pr2_rovers", "examples.pybullet.pr2_rovers.run", needs="pybullet", limit=120.0),
    Example("pr2_belief", "examples.pybullet.pr2_belief.run", needs="pybullet", limit=math.inf),
    Example(
        "tamp", "examples.pybullet.tamp.run", needs="pybullet", limit=120.0, upstream=TAMP_UPSTREAM
    ),
    Example(
        "turtlebot_rovers", "examples.pybullet.turtlebot_rovers.run", needs="pybullet", limit=120.0
    ),
    Example(
        "turtlebots",
        "examples.pybullet.turtlebots.run",
        needs="pybullet",
        limit=300.0,
        upstream=TURTLEBOTS_UPSTREAM,
    ),
)

#: ``--quick``'s defaults
QUICK: dict[str, object] = {"only": ["blocksworld"], "timeout": 60.0}

#: [s] the runner's allowance, beyond an example's own time limit, for loading its world
#: (pybullet scenes, sampled roadmaps) and re-checking its plans
SETUP_SECONDS = 60.0


def allowed_seconds(example: Example, timeout: float | None, unlimited: float) -> float:
    """How long the runner lets ``example`` run [s]: ``timeout`` when given, else its own time
    limit plus :data:`SETUP_SECONDS`, ``unlimited`` when it has none, 120 s when it states
    nothing."""
    if timeout is not None:
        return timeout
    if example.limit is None:
        return DEFAULT_TIMEOUT
    if math.isinf(example.limit):
        return unlimited
    return example.limit + SETUP_SECONDS


#: PDDLStream's examples predate NumPy 2 and use names it removed; the runner puts those
#: aliases back in the example's process (an environment fix, the examples stay unmodified),
#: and ``numpy.math`` (the standard ``math`` module, used by pr2_rovers' streams)
NUMPY_ALIASES = (
    ("product", "prod"),
    ("cumproduct", "cumprod"),
    ("alltrue", "all"),
    ("sometrue", "any"),
    ("mat", "asmatrix"),
)

#: the examples' standard input: Enter pressed at every prompt (pr2_belief waits for the user
#: before each of its planning rounds; ``wait_for_user`` reads a line)
PRESSES = "\n" * 10_000

#: loaded modules whose file lies in the checkout's own package mean the alias was bypassed
_GUARD = (
    "import atexit, os, sys\n"
    "def _guard():\n"
    "    bad = sorted(n for n, m in list(sys.modules.items())\n"
    "                 if (getattr(m, '__file__', None) or '').startswith({pkg!r}))\n"
    "    if bad:\n"
    "        print('LOADED FROM CHECKOUT:', bad, file=sys.stderr); os._exit(97)\n"
    "atexit.register(_guard)\n"
    "import numpy\n"
    "for _old, _new in {numpy_aliases!r}:\n"
    "    if _old not in dir(numpy):\n"
    "        setattr(numpy, _old, getattr(numpy, _new) if isinstance(_new, str) else _new)\n"
    "if 'math' not in dir(numpy):\n"
    "    import math as _math\n"
    "    numpy.math = _math\n"
    "if not os.environ.get('DISPLAY'):\n"
    "    import types\n"
    "    class _Null:\n"
    "        def __init__(self, *a, **k): pass\n"
    "        def __call__(self, *a, **k): return _Null()\n"
    "        def __getattr__(self, name): return _Null()\n"
    "        def __iter__(self): return iter(())\n"
    "        def __getitem__(self, key): return _Null()\n"
    "        def geometry(self, *a): return '400x200+0+0'\n"
    "        def winfo_screenwidth(self): return 800\n"
    "        def winfo_screenheight(self): return 600\n"
    "        def __int__(self): return 0\n"
    "        def __float__(self): return 0.0\n"
    "    _tk = types.ModuleType('tkinter')\n"
    "    _tk.Tk = _tk.Canvas = _tk.Toplevel = _Null\n"
    "    _tk.LAST = 'last'\n"
    "    sys.modules['tkinter'] = _tk\n"
    "sys.argv = ['sdar_tamp.compat.pddlstream', *sys.argv[1:]]\n"
    "from sdar_tamp.compat.pddlstream.__main__ import main\n"
    "sys.exit(main())\n"
)


def run_example(
    checkout: Path, example: Example, timeout: float, seed: int | None = None
) -> dict[str, object]:
    """Run one example; returns its name, result, time [s] and details (``solve_seconds``:
    the time of the program's solve calls). ``seed``: Python's and NumPy's random generators
    are seeded with it before the program starts (an unseeded example then runs the same way
    each time)."""
    if example.needs and importlib.util.find_spec(example.needs) is None:
        return {
            "example": example.name,
            "result": f"skipped: needs {example.needs!r} (pip install sdar-tamp[pybullet])",
            "passed": False,
            "skipped": True,
            "seconds": 0.0,
            "solve_calls": 0,
            "plans": 0,
            "solve_seconds": 0.0,
        }
    with tempfile.TemporaryDirectory() as scratch:
        report = Path(scratch) / "report.json"
        guard = _GUARD.format(
            pkg=str(checkout / "pddlstream") + os.sep, numpy_aliases=NUMPY_ALIASES
        )
        if seed is not None:
            guard = f"import random, numpy\nrandom.seed({seed})\nnumpy.random.seed({seed})\n{guard}"
        command = [
            sys.executable,
            "-c",
            guard,
            "--report",
            str(report),
            "-m",
            example.module,
            *example.args,
        ]
        env = dict(os.environ)
        extra = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
        env["PYTHONPATH"] = os.pathsep.join([str(ROOT), str(checkout), *extra])
        env.setdefault("MPLBACKEND", "Agg")
        env.pop("DISPLAY", None)
        start = time.perf_counter()
        try:
            done = subprocess.run(
                command,
                cwd=checkout,
                env=env,
                input=PRESSES,
                capture_output=True,
                text=True,
                timeout=timeout,
            )
            seconds = time.perf_counter() - start
            returncode: int | None = done.returncode
            stderr = done.stderr
        except subprocess.TimeoutExpired as expired:
            seconds = time.perf_counter() - start
            returncode = None
            stderr = (expired.stderr or b"").decode() if isinstance(expired.stderr, bytes) else ""
        record = json.loads(report.read_text()) if report.exists() else {"calls": []}
    calls = record.get("calls", [])
    solved = [c for c in calls if c.get("solved")]
    invalid = [c for c in solved if not c.get("valid")]
    if returncode == 97:
        result = "alias bypassed"
    elif invalid:
        result = f"INVALID plan: {invalid[0].get('error')}"
    elif solved:
        result = "solved"
        if returncode is None:  # a closed-loop program (plan, execute, plan again) still going
            result = f"solved, {len(solved)} plan(s) (then: stopped at {timeout:g} s)"
        elif returncode != 0 and record.get("exception"):
            result = f"solved (then: {str(record['exception'])[:60]})"
    elif returncode is None:
        result = f"timeout ({timeout:g} s)"
    elif record.get("exception"):
        result = f"error: {str(record['exception'])[:90]}"
    elif returncode != 0:
        tail = [line for line in stderr.strip().splitlines() if line.strip()][-1:]
        result = f"error (exit {returncode}): {' '.join(tail)[:90]}"
    else:
        result = "no plan"
    return {
        "example": example.name,
        "result": result,
        "passed": bool(solved) and not invalid and returncode != 97,
        "seconds": round(seconds, 2),
        "solve_calls": len(calls),
        "plans": len(solved),
        "solve_seconds": round(sum(float(c.get("seconds", 0.0)) for c in calls), 3),
        "solve_cpu": round(sum(float(c.get("cpu_seconds", 0.0)) for c in calls), 3),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("checkout", nargs="?", default=os.environ.get("PDDLSTREAM_PATH"))
    parser.add_argument(
        "--timeout",
        type=float,
        default=None,
        help="[s] per example (default: its own time limit + 60 s; 120 s when it states none)",
    )
    parser.add_argument(
        "--unlimited",
        type=float,
        default=600.0,
        help="[s] for an example with no time limit of its own (kuka, pr2, pr2_belief)",
    )
    parser.add_argument("--only", nargs="*", default=None, help="example names to run")
    parser.add_argument(
        "--repeat", type=int, default=1, help="runs per example (unseeded ones vary: pass rates)"
    )
    parser.add_argument("--quick", action="store_true", help="one example (blocksworld)")
    args = parser.parse_args(argv)
    if args.quick:  # explicit options still win
        parser.set_defaults(**QUICK)
        args = parser.parse_args(argv)
    if args.repeat < 1:
        parser.error(f"--repeat must be >= 1; got {args.repeat}")
    if not args.checkout or not (Path(args.checkout) / "examples").is_dir():
        why = (
            f"no PDDLStream checkout (pass its path or set PDDLSTREAM_PATH); got {args.checkout!r}"
        )
        print(f"skipped: {why}")
        print(json.dumps({"skipped": why, "quick": args.quick}))
        return 0
    checkout = Path(args.checkout).resolve()
    chosen = [e for e in EXAMPLES if args.only is None or e.name in args.only]
    rows = []
    print(f"{'example':28} {'result':60} {'time [s]':>8}")
    rates: dict[str, str] = {}
    for example in chosen:
        runs = []
        for _ in range(args.repeat):
            allowed = allowed_seconds(example, args.timeout, args.unlimited)
            row = run_example(checkout, example, allowed)
            runs.append(row)
            print(f"{row['example']:28} {row['result']!s:60} {row['seconds']:8.2f}", flush=True)
            if not row["passed"] and example.upstream:
                print(f"{'':28} (PDDLStream itself: {example.upstream})", flush=True)
        rows.extend(runs)
        rates[example.name] = f"{sum(bool(r['passed']) for r in runs)}/{len(runs)}"
    passed = sum(bool(r["passed"]) for r in rows)
    print(f"passed {passed} of {len(rows)}")
    summary: dict[str, object] = {
        "passed": passed,
        "total": len(rows),
        "failed": sorted({str(r["example"]) for r in rows if not r["passed"]}),
        "fail_in_pddlstream_too": [e.name for e in chosen if e.upstream],
        "seconds": {str(r["example"]): r["seconds"] for r in rows},
        "quick": args.quick,
    }
    if args.repeat > 1:
        summary["pass_rates"] = rates
    print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
