"""Instance files: generate one instance or a named suite into files, and draw an instance
file (``sdar generate`` and ``sdar show`` call these).

Each writes files only where it is told to and returns what it wrote.
"""

from __future__ import annotations

from pathlib import Path

from sdar_tamp.world.draw import draw_instance
from sdar_tamp.world.generators import Acceptance, generate_instance
from sdar_tamp.world.instance import load_instance, save_instance
from sdar_tamp.world.suites import generate_suite as _generate_suite
from sdar_tamp.world.suites import suite_members


def generate(
    family: str, objects: int, seed: int, out: Path, accept: Acceptance | None = None
) -> Path:
    """Generate one instance of ``family`` (R, S, D, M) and write it to ``out`` (YAML);
    ``accept``: the generator's acceptance test."""
    return save_instance(generate_instance(family, objects, seed, accept=accept), Path(out))


def generate_suite(suite: str, out_dir: Path, accept: Acceptance | None = None) -> list[Path]:
    """Write the named suite (``paper``, ``stress`` or ``dense``) into ``out_dir``."""
    return _generate_suite(suite, Path(out_dir), accept)


def suite_files(suite: str, out_dir: Path) -> list[Path]:
    """The files :func:`generate_suite` writes for ``suite`` into ``out_dir``."""
    return [Path(out_dir) / f"{m.name}.yaml" for m in suite_members(suite)]


def show_instance(instance_path: Path, out: Path) -> Path:
    """Draw the instance file at ``instance_path`` to the image ``out`` (e.g. ``.png``)."""
    return draw_instance(load_instance(Path(instance_path)), Path(out))
