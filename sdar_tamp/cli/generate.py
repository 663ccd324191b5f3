"""``sdar generate``: one rearrangement instance of a family, or a whole named suite."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from sdar_tamp.arguments import COUNT, SEED, output_file, output_folder
from sdar_tamp.cli.log_options import FORCE_HELP
from sdar_tamp.errors import SdarError

#: The generator's families and the named suites, spelt out so that the command line starts
#: without NumPy (tests/cli checks they match sdar_tamp.world.generators and .suites).
CLI_FAMILIES = ("R", "S", "D", "M", "N")
CLI_SUITES = ("paper", "stress", "dense", "families")


def cmd_generate(args: argparse.Namespace) -> int:
    """Generate a rearrangement instance (one family) or a whole suite of instance files.
    With --scene, inside that cell: its workspace and default object, its arms' reach (the
    acceptance test plans with its robots), the instances naming it. Shipped cells:
    `sdar cells`."""
    from sdar_tamp.world.instance_files import generate, generate_suite, suite_files
    from streams.context import WorldContext
    from streams.feasibility import ProofCheck  # refuses samples proven unsolvable

    check = ProofCheck(WorldContext.load(args.scene) if args.scene is not None else None)

    if args.suite is not None:
        if args.family is not None or args.objects is not None:
            raise SdarError("sdar generate: --suite cannot be combined with --family/--objects")
        if args.suite == "families" and args.scene is None:
            raise SdarError(
                "sdar generate --suite families: expected --scene CELL (the suite is made for "
                "a given cell's workspace and arms; the shipped cells: `sdar cells`)"
            )
        output_folder(args.output)
        taken = [p for p in suite_files(args.suite, args.output) if p.exists()]
        if taken and not args.force:
            raise SdarError(
                f"--output: {len(taken)} instance file(s) of suite {args.suite!r} exist in "
                f"{str(args.output)!r} (e.g. {taken[0].name}); pass --force to replace them"
            )
        paths = generate_suite(args.suite, args.output, check, args.scene)
        print(f"wrote {len(paths)} instances of suite {args.suite!r} to {args.output}")
        return 0
    if args.family is None or args.objects is None:
        raise SdarError("sdar generate needs --family and --objects, or --suite")
    output_file(args.output, suffixes=(".yaml", ".yml"), force=args.force)
    path = generate(args.family, args.objects, args.seed, args.output, check, args.scene)
    print(f"wrote {path}")
    return 0


def add_generate_parser(sub: argparse._SubParsersAction[Any]) -> None:
    """Register ``sdar generate``."""
    generate = sub.add_parser(
        "generate", help="generate rearrangement instances", description=cmd_generate.__doc__
    )
    generate.add_argument("--family", choices=CLI_FAMILIES, help="instance family")
    generate.add_argument("--objects", type=COUNT.parse, help="number of objects")
    generate.add_argument("--seed", type=SEED.parse, default=0, help="random seed (default: 0)")
    generate.add_argument("--suite", choices=CLI_SUITES, help="a whole suite")
    generate.add_argument(
        "-o",
        "--output",
        type=Path,
        required=True,
        help="instance file (.yaml), or folder with --suite",
    )
    generate.add_argument("--force", action="store_true", help=FORCE_HELP)
    generate.add_argument(
        "--scene",
        type=Path,
        default=None,
        help="generate inside this cell (scene file; the shipped ones: `sdar cells`)",
    )
    generate.set_defaults(func=cmd_generate)
