"""Instance files: generate one instance or a named suite into files, and draw an instance
file (``sdar generate`` and ``sdar show`` call these).

Each writes files only where it is told to and returns what it wrote.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

from sdar_tamp.world.draw import draw_instance
from sdar_tamp.world.generators import Acceptance, GeneratorOptions, generate_instance
from sdar_tamp.world.instance import load_instance, save_instance
from sdar_tamp.world.scene import load_scene
from sdar_tamp.world.suites import generate_suite as _generate_suite
from sdar_tamp.world.suites import suite_members


def cell_options(scene: Path | None, folder: Path) -> tuple[GeneratorOptions | None, str | None]:
    """The generator's options for the cell ``scene`` (its workspace, default object and
    grippers; None: the defaults) and the ``scene`` key of instances written to ``folder``
    (the scene file relative to it)."""
    if scene is None:
        return None, None
    cell = load_scene(Path(scene))
    options = GeneratorOptions(
        size=cell.object_size, workspace=cell.workspace, grasp=cell.grasp_limits
    )
    key = os.path.relpath(Path(scene).resolve(), Path(folder).resolve())
    return options, Path(key).as_posix()


def generate(
    family: str,
    objects: int,
    seed: int,
    out: Path,
    accept: Acceptance | None = None,
    scene: Path | None = None,
) -> Path:
    """Generate one instance of ``family`` (R, S, D, M) and write it to ``out`` (YAML);
    ``accept``: the generator's acceptance test; ``scene``: generate inside that cell (its
    workspace and default object) and name it in the instance."""
    options, key = cell_options(scene, Path(out).parent)
    instance = generate_instance(family, objects, seed, options, accept=accept)
    return save_instance(dataclasses.replace(instance, scene=key), Path(out))


def generate_suite(
    suite: str, out_dir: Path, accept: Acceptance | None = None, scene: Path | None = None
) -> list[Path]:
    """Write the named suite (``paper``, ``stress`` or ``dense``) into ``out_dir``
    (``scene``: inside that cell, as :func:`generate`)."""
    options, key = cell_options(scene, Path(out_dir))
    return _generate_suite(suite, Path(out_dir), accept, options, key)


def suite_files(suite: str, out_dir: Path) -> list[Path]:
    """The files :func:`generate_suite` writes for ``suite`` into ``out_dir``."""
    return [Path(out_dir) / f"{m.name}.yaml" for m in suite_members(suite)]


def show_instance(instance_path: Path, out: Path) -> Path:
    """Draw the instance file at ``instance_path`` to the image ``out`` (e.g. ``.png``)."""
    return draw_instance(load_instance(Path(instance_path)), Path(out))
