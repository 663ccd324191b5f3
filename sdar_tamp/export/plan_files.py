"""Exporting plans: a loaded plan, or a plan file, to one of :data:`FORMATS`.

:func:`export_plan` picks the writer of a format; :func:`export_plan_file` reads a plan file,
checks where the output goes and exports it (``sdar export``). NumPy and the writers are
imported on use.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from sdar_tamp.arguments import output_file, output_folder
from sdar_tamp.errors import ParameterError
from sdar_tamp.export.formats import CSV_RATE, FORMATS

if TYPE_CHECKING:
    from sdar_tamp.export.urscript import ServoSettings
    from sdar_tamp.plan_file import PlanFile
    from sdar_tamp.world.scene import Scene

#: What ``-o`` names per format, and the default name next to the plan.
_DEFAULT_SUFFIX = {"joint-trajectory": ".trajectory.json", "csv": ".csv", "urscript": ".urscript"}


def default_output(plan_path: Path, fmt: str) -> Path:
    """Where ``fmt`` goes without ``-o``: next to the plan, ``PLAN`` + a suffix
    (``run.json`` -> ``run.trajectory.json``, ``run.csv``, folder ``run.urscript``)."""
    _check_format(fmt)
    plan_path = Path(plan_path)
    stem = plan_path.stem if plan_path.suffix.lower() == ".json" else plan_path.name
    return plan_path.with_name(stem + _DEFAULT_SUFFIX[fmt])


def export_plan(
    plan: PlanFile,
    fmt: str,
    output: Path,
    *,
    servo: ServoSettings | None = None,
    rate: float = CSV_RATE,
    scene: Scene | None = None,
) -> list[Path]:
    """Write ``plan`` as ``fmt`` (one of :data:`FORMATS`) to ``output`` (a file; a folder for
    ``urscript``); returns the files written. ``scene``: the plan's cell (``urscript`` checks
    its robot descriptions: UR arms only)."""
    from sdar_tamp.export.joint_trajectory import write_joint_trajectory
    from sdar_tamp.export.table import write_csv
    from sdar_tamp.export.urscript import write_urscript

    _check_format(fmt)
    if fmt == "joint-trajectory":
        return [write_joint_trajectory(plan, output)]
    if fmt == "csv":
        return [write_csv(plan, output, rate)]
    return write_urscript(plan, output, servo, scene)


def export_plan_file(
    plan_path: Path,
    fmt: str,
    output: Path | None = None,
    *,
    force: bool = False,
    servo: ServoSettings | None = None,
    rate: float = CSV_RATE,
    scene: Scene | None = None,
) -> list[Path]:
    """Read ``plan_path`` (its arms checked against ``scene``'s when given), check where the
    output goes (existing files are refused unless ``force``) and export; returns the files
    written."""
    from sdar_tamp.export.urscript import script_name
    from sdar_tamp.plan_reading import load_plan

    _check_format(fmt)
    plan = load_plan(plan_path, scene.layout if scene is not None else None)
    target = Path(output) if output is not None else default_output(plan_path, fmt)
    if fmt == "urscript":
        output_folder(target)
        taken = [target / script_name(a) for a in plan.arm_names]
        taken = [p for p in taken if p.exists()]
        if taken and not force:
            raise ParameterError(
                f"--output: {str(taken[0])!r} exists; pass --force to replace it, or choose "
                "another folder"
            )
    else:
        suffix = ".json" if fmt == "joint-trajectory" else ".csv"
        output_file(target, suffixes=(suffix,), force=force)
    return export_plan(plan, fmt, target, servo=servo, rate=rate, scene=scene)


def _check_format(fmt: str) -> None:
    if fmt not in FORMATS:
        raise ParameterError(f"format must be one of {', '.join(FORMATS)}; got {fmt!r}")
