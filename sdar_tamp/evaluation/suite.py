"""The instances a benchmark runs: a shipped suite or a folder of instance files, filtered."""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from sdar_tamp.errors import ParameterError, SdarError
from sdar_tamp.evaluation.results import instance_sort_key


@dataclass(frozen=True)
class SuiteEntry:
    """One instance file of a suite."""

    path: Path
    name: str
    family: str
    objects: int


def suite_entries(
    suite: str | Path, only: Sequence[str] | None = None, max_objects: int | None = None
) -> list[SuiteEntry]:
    """The instances of ``suite`` (a shipped suite name or a folder of instance YAML files),
    keeping the names in ``only`` (instance or file names) and at most ``max_objects``."""
    from sdar_tamp.world.instance import load_instance

    folder, _ = suite_folder(suite)
    entries = []
    for path in sorted(folder.glob("*.yaml")):
        inst = load_instance(path)
        family = inst.family or re.sub(r"\d.*", "", inst.name)
        entries.append(SuiteEntry(path, inst.name, family, len(inst.objects)))
    names_seen = [e.name for e in entries]
    if len(set(names_seen)) < len(names_seen):
        raise SdarError(f"{folder}: two instance files share an instance name")
    if only:
        known = {e.name for e in entries} | {e.path.stem for e in entries}
        missing = [n for n in only if n not in known]
        if missing:
            raise ParameterError(f"only: no instance {', '.join(missing)} in {folder}")
        entries = [e for e in entries if e.name in only or e.path.stem in only]
    if max_objects is not None:
        entries = [e for e in entries if e.objects <= max_objects]
    if not entries:
        raise ParameterError(f"no instance of {folder} is selected")
    return sorted(entries, key=lambda e: (e.objects, instance_sort_key(e.name)))


def suite_folder(suite: str | Path) -> tuple[Path, bool]:
    """The folder of ``suite`` and whether it is a shipped suite.

    A :class:`Path`, or a string with a path separator (``./paper``, ``/data/tables``), is a
    folder. A bare name is the shipped suite of that name; a folder of that name in the
    working directory is used only when no suite is shipped under it. A bare name that is
    both a shipped suite and a folder of instance files here is refused as ambiguous (write
    ``./name`` for the folder); a folder of that name without instance files (an earlier
    ``--out``, say) does not hide the shipped suite."""
    from sdar_tamp.resources import domain_file

    shipped_root = domain_file("dual_arm_rearrangement").parent / "suites"
    shipped = sorted(p.name for p in shipped_root.iterdir() if p.is_dir() and p.name[0] != "_")
    text = str(suite)
    bare = isinstance(suite, str) and "/" not in text and os.sep not in text
    local = Path(text)
    if bare and text in shipped:
        if local.is_dir() and any(local.glob("*.yaml")):
            raise ParameterError(
                f"suite {text!r} is both a shipped suite and a folder of instances here; "
                f"write ./{text} for the folder, or run from another directory for the "
                "shipped suite"
            )
        return shipped_root / text, True
    if local.is_dir():
        return local, False
    raise ParameterError(f"suite must be a folder or one of {', '.join(shipped)}; got {text!r}")


def suite_label(suite: str | Path) -> str:
    """How the settings record names ``suite``: a folder by its resolved path, a shipped
    suite by its name."""
    folder, shipped = suite_folder(suite)
    return str(suite) if shipped else str(folder.resolve())
