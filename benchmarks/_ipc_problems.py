"""IPC problem collections for the classical benchmarks: every problem file of a suite folder
(one folder per domain) with its domain file, in natural order."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any


def _natural(name: str) -> list[Any]:
    return [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", name)]


def domain_file(problem: Path) -> Path | None:
    """The domain file of an IPC problem file: ``domain.pddl`` beside it, or one of the
    per-problem names of the IPC collections (``domain_p01.pddl``, ``domain-p01.pddl`` or
    ``p01-domain.pddl`` for ``p01.pddl``, ``p01-domain.pddl`` for ``p01-airport1-p1.pddl``)."""
    folder, name, stem = problem.parent, problem.name, problem.stem
    candidates = [
        folder / f"domain_{name}",
        folder / f"domain-{name}",
        folder / f"{stem.split('-')[0]}-domain.pddl",
        folder / "domain.pddl",
    ]
    return next((c for c in candidates if c.is_file()), None)


def suite_problems(
    suite: Path, selection: dict[str, tuple[str, ...]] | None = None
) -> list[tuple[str, str, Path, Path]]:
    """Every problem (with a domain file, see :func:`domain_file`) of every domain folder of
    ``suite``, or only those named in ``selection``."""
    cases = []
    for folder in sorted(p for p in suite.iterdir() if p.is_dir()):
        if selection is not None and folder.name not in selection:
            continue
        problems = [p for p in folder.glob("*.pddl") if "domain" not in p.name]
        if selection is not None:
            problems = [p for p in problems if p.stem in selection[folder.name]]
        for problem in sorted(problems, key=lambda p: _natural(p.name)):
            domain = domain_file(problem)
            if domain is not None:
                cases.append((folder.name, problem.stem, domain, problem))
    return cases


def first_per_domain(
    cases: list[tuple[str, str, Path, Path]], k: int
) -> list[tuple[str, str, Path, Path]]:
    """The first ``k`` cases of each domain (cases are in natural order per domain)."""
    seen: dict[str, int] = {}
    out = []
    for case in cases:
        seen[case[0]] = seen.get(case[0], 0) + 1
        if seen[case[0]] <= k:
            out.append(case)
    return out
