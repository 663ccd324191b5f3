"""Benchmark of the infeasibility proofs (:func:`streams.feasibility.prove_unplannable`): the
time to prove or pass every instance of the `paper` suite, the shipped `stress` suite, and the
`stress` suite as it was generated before the generator refused provably unsolvable samples
(the same seeds without the acceptance test).

Prints one line per instance, then as its last line one JSON object with the figures.

    python benchmarks/bench_feasibility.py            # the full run (49 instances)
    python benchmarks/bench_feasibility.py --quick    # one instance of each set: seconds

``--quick``: ``paper`` R4, ``stress`` R20 and ``stress_before`` R20 (which the proofs refuse);
the JSON keys are the same, plus ``"quick": true``.
"""

from __future__ import annotations

import argparse
import json
import time

from sdar_tamp.world.generators import GeneratorOptions, generate_instance
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.suites import load_suite, suite_members
from streams.context import WorldContext
from streams.feasibility import prove_unplannable

#: ``--quick``: the instances of each set, by name
QUICK = {"paper": ("R4",), "stress": ("R20",), "stress_before": ("R20",)}


def _old_stress(names: tuple[str, ...] | None = None) -> tuple[Instance, ...]:
    return tuple(
        generate_instance(
            m.family, m.n_objects, m.seed, GeneratorOptions(gap=m.gap or 0.0), name=m.name
        )
        for m in suite_members("stress")
        if names is None or m.name in names
    )


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one instance of each set")
    args = ap.parse_args(argv)
    ctx = WorldContext.load()
    figures: dict[str, object] = {}
    for label, instances in (
        ("paper", load_suite("paper")),
        ("stress", load_suite("stress")),
        ("stress_before", _old_stress(QUICK["stress_before"] if args.quick else None)),
    ):
        if args.quick:
            instances = tuple(i for i in instances if i.name in QUICK[label])
        times: dict[str, float] = {}
        proven: dict[str, list[str]] = {}
        for inst in instances:
            started = time.perf_counter()
            proof = prove_unplannable(ctx, inst)
            times[inst.name] = round(time.perf_counter() - started, 3)
            verdict = "passes" if proof is None else " | ".join(proof.lines())
            print(f"{label:13s} {inst.name:5s} {times[inst.name]:6.2f} s  {verdict}", flush=True)
            if proof is not None:
                proven[inst.name] = list(proof.lines())
        figures[label] = {"seconds": times, "max_seconds": max(times.values()), "proven": proven}
    figures["quick"] = args.quick
    print(json.dumps(figures))


if __name__ == "__main__":
    main()
