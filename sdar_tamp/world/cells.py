"""The shipped cells: the scene files of ``domains/dual_arm_rearrangement/cells``.

A cell is a scene file (see ``docs/robots.md``): its name is the file's stem, its description
the first comment line of the file. :func:`shipped_cells` lists them in name order;
:func:`cell_path` finds one by name.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from sdar_tamp.textfile import read_text
from sdar_tamp.world._yaml import file_error
from sdar_tamp.world.errors import SceneError
from sdar_tamp.world.scene import domain_path

#: The folder of the shipped cells, inside ``domains/dual_arm_rearrangement``.
CELLS_FOLDER = "cells"


@dataclass(frozen=True)
class CellEntry:
    """A shipped cell: its name (the file's stem), scene file and one-line description."""

    name: str
    path: Path
    description: str


def cells_dir() -> Path:
    return domain_path(CELLS_FOLDER)


def describe(path: Path) -> str:
    """The first comment line of the scene file ``path`` (without ``#``), or ``""``."""
    for line in read_text(path, file_error(SceneError)).splitlines():
        stripped = line.strip()
        if stripped.startswith("#"):
            return stripped.lstrip("#").strip()
        if stripped:
            return ""
    return ""


def shipped_cells() -> tuple[CellEntry, ...]:
    """Every shipped cell, in name order."""
    paths = sorted(cells_dir().glob("*.yaml"))
    return tuple(CellEntry(p.stem, p, describe(p)) for p in paths)


def is_cell_file(path: Path) -> bool:
    """Whether ``path`` is a scene file (a YAML mapping with ``arms``), not an instance."""
    import yaml

    try:
        data = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return False
    return isinstance(data, dict) and "arms" in data


def cell_path(name: str) -> Path:
    """The scene file of the shipped cell ``name``.

    Raises:
        SceneError: no shipped cell has that name (the message lists them).
    """
    for cell in shipped_cells():
        if cell.name == name:
            return cell.path
    names = ", ".join(c.name for c in shipped_cells())
    raise SceneError(f"no shipped cell {name!r}; the shipped cells are: {names}")
