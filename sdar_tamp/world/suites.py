"""Named suites of instances, as folders of YAML files.

* ``paper``: R, S and D with every object count 4 to 12 (27 instances, names ``R4`` ... ``D12``)
  and the mixed cases ``M1`` to ``M10`` (12 objects each): 37 instances.
* ``stress``: R, S, D and mixed with 16, 20 and 24 objects (``R16`` ... ``D24``; the mixed ones
  are named ``Mn16``, ``Mn20``, ``Mn24`` since ``M#`` is an index in the paper): 12 instances.
* ``dense``: the dense family ``N`` with 16, 20 and 24 objects at the paper's clearance
  (``N16``, ``N20``, ``N24``): mixed sizes, neighbours trading places, turned goals.
* ``families``: the paper's four families M, R, D and S with 12, 16, 20 and 24 objects, two
  seeded instances each (``M12-1``, ``M12-2`` ... ``S24-2``: 32 instances) at the generator's
  default clearance, meant for a cell given with ``--scene`` (its workspace, object and
  arms). Its seeds do not depend on the cell, so cells with one workspace get the same
  instances unless a cell's acceptance test refuses a sample the others accept.

The shipped copies of the ``families`` suite on the cells of the shared 1.2 m x 1.0 m table
are the suites ``table_1arm`` ... ``table_4arm`` (:data:`CELL_SUITES`: suite name -> cell).

Seeds are fixed per instance (:func:`suite_members`), so a suite regenerates identically. The
shipped copies live in ``domains/dual_arm_rearrangement/suites/<suite>/``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from importlib.resources import files
from pathlib import Path

from sdar_tamp.world.errors import SuiteError
from sdar_tamp.world.generators import Acceptance, GeneratorOptions, generate_instance
from sdar_tamp.world.instance import Instance, load_instance, save_instance

SUITES = ("paper", "stress", "dense", "families")
_FAMILY_SEED = {"R": 1000, "S": 2000, "D": 3000, "M": 4000, "N": 5000}
STRESS_GAP = 0.01  # [m]
#: The shipped ``families`` suites: suite name -> the shipped cell they were generated in.
CELL_SUITES = {f"table_{k}arm": f"ur5e_table_{k}arm" for k in (1, 2, 3, 4)}
#: Object counts and instances per family and count of the ``families`` suite.
FAMILY_SIZES = (12, 16, 20, 24)
FAMILY_COPIES = 2


@dataclass(frozen=True)
class SuiteMember:
    """How one instance of a suite is generated."""

    name: str
    family: str
    n_objects: int
    seed: int
    gap: float | None = None  # footprint clearance [m]; None: the generator's default


def suite_members(suite: str) -> tuple[SuiteMember, ...]:
    """The instances of a named suite, in order."""
    if suite == "paper":
        members = [
            SuiteMember(f"{f}{n}", f, n, _FAMILY_SEED[f] + n) for f in "RSD" for n in range(4, 13)
        ]
        members += [SuiteMember(f"M{k}", "M", 12, _FAMILY_SEED["M"] + k) for k in range(1, 11)]
        return tuple(members)
    if suite == "stress":
        # 24 objects do not fit with the default (grasp) clearance: the stress suite keeps
        # 1 cm, so some of its objects may be boxed in where they rest or at their goals
        members = [
            SuiteMember(f"{f}{n}", f, n, _FAMILY_SEED[f] + n, STRESS_GAP)
            for f in "RSD"
            for n in (16, 20, 24)
        ]
        members += [
            SuiteMember(f"Mn{n}", "M", n, _FAMILY_SEED["M"] + 100 + n, STRESS_GAP)
            for n in (16, 20, 24)
        ]
        return tuple(members)
    if suite == "dense":
        return tuple(SuiteMember(f"N{n}", "N", n, _FAMILY_SEED["N"] + n) for n in (16, 20, 24))
    if suite == "families" or suite in CELL_SUITES:
        return tuple(
            SuiteMember(f"{f}{n}-{j}", f, n, _FAMILY_SEED[f] + 300 + 10 * n + j)
            for f in "MRDS"
            for n in FAMILY_SIZES
            for j in range(1, FAMILY_COPIES + 1)
        )
    known = [*SUITES, *CELL_SUITES]
    raise SuiteError(f"unknown suite {suite!r}; expected one of {known}")


def build_suite(
    suite: str, accept: Acceptance | None = None, options: GeneratorOptions | None = None
) -> tuple[Instance, ...]:
    """Generate every instance of a suite in memory (``accept``: the generator's acceptance
    test, see :func:`~sdar_tamp.world.generators.generate_instance`; ``options``: the
    generator's, e.g. another cell's workspace and object, each member's gap applied)."""
    base = options or GeneratorOptions()
    return tuple(
        generate_instance(
            m.family,
            m.n_objects,
            m.seed,
            base if m.gap is None else dataclasses.replace(base, gap=m.gap),
            name=m.name,
            accept=accept,
        )
        for m in suite_members(suite)
    )


def generate_suite(
    suite: str,
    out_dir: Path,
    accept: Acceptance | None = None,
    options: GeneratorOptions | None = None,
    scene: str | None = None,
) -> list[Path]:
    """Write a suite as ``out_dir/<name>.yaml`` files; returns the paths in suite order.
    ``scene``: the instances' ``scene`` key (a scene file relative to ``out_dir``)."""
    out = Path(out_dir)
    return [
        save_instance(dataclasses.replace(i, scene=scene), out / f"{i.name}.yaml")
        for i in build_suite(suite, accept, options)
    ]


def shipped_suite_dir(suite: str) -> Path:
    suite_members(suite)  # validates the name
    return Path(str(files("domains") / "dual_arm_rearrangement" / "suites" / suite))


def load_suite(suite: str, directory: Path | None = None) -> tuple[Instance, ...]:
    """Load a suite: from ``directory`` if given, else the shipped copy, in suite order."""
    if directory is None and suite == "families":
        raise SuiteError(
            "suite 'families' is made for a given cell and has no shipped copy of its own; "
            f"the shipped ones are {list(CELL_SUITES)} (or pass the folder it was written to)"
        )
    folder = Path(directory) if directory is not None else shipped_suite_dir(suite)
    members = suite_members(suite)
    missing = [m.name for m in members if not (folder / f"{m.name}.yaml").is_file()]
    if missing:
        raise SuiteError(f"suite {suite!r} in {folder}: missing instance files {missing}")
    return tuple(load_instance(folder / f"{m.name}.yaml") for m in members)
