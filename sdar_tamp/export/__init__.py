"""Plan export: a plan file as ROS-style joint trajectories, a CSV table or URScript programs.

``sdar export PLAN.json --format joint-trajectory|csv|urscript [-o OUT]``; in Python,
:func:`export_plan` (a loaded plan) or :func:`export_plan_file` (a plan file, with the command's
output checks). The formats are described in their modules. Importing the package is light
(the CLI imports it); the writers and NumPy load on first use.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from sdar_tamp.export.formats import CSV_RATE, FORMATS
from sdar_tamp.export.plan_files import default_output, export_plan, export_plan_file

if TYPE_CHECKING:
    from sdar_tamp.export.joint_trajectory import (
        joint_trajectory_document,
        write_joint_trajectory,
    )
    from sdar_tamp.export.table import csv_header, write_csv
    from sdar_tamp.export.timeline import sample_derivatives
    from sdar_tamp.export.urscript import ServoSettings, urscript_programs, write_urscript

_LAZY = {
    "joint_trajectory_document": "joint_trajectory",
    "write_joint_trajectory": "joint_trajectory",
    "csv_header": "table",
    "write_csv": "table",
    "sample_derivatives": "timeline",
    "ServoSettings": "urscript",
    "urscript_programs": "urscript",
    "write_urscript": "urscript",
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{module}"), name)


__all__ = [
    "CSV_RATE",
    "FORMATS",
    "ServoSettings",
    "csv_header",
    "default_output",
    "export_plan",
    "export_plan_file",
    "joint_trajectory_document",
    "sample_derivatives",
    "urscript_programs",
    "write_csv",
    "write_joint_trajectory",
    "write_urscript",
]
