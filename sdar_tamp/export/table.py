"""A plan as one CSV table at a fixed rate (50 Hz by default).

Columns: ``time`` [s], every arm's joint positions [rad] under the plan's joint names (the
arms in plan order, one to four or more; each arm with its own joint count), then per arm
``<arm>_gripper`` (1 closed, 0 open: the commanded state, from the event's time on) and
``<arm>_held`` (the object in that gripper, empty when open). Rows at
``k / rate`` for ``k = 0 .. ceil(duration * rate)``; positions are linear between the plan's
samples and hold the final configuration after the end (the last row may pass the end by less
than one period).
"""

from __future__ import annotations

import csv
from pathlib import Path

from sdar_tamp.errors import ParameterError
from sdar_tamp.export.formats import CSV_RATE
from sdar_tamp.export.timeline import controller_grid, gripper_states, positions_at
from sdar_tamp.plan_file import PlanFile


def csv_header(plan: PlanFile) -> list[str]:
    """The header row."""
    names = [j for info in plan.arms for j in info.joints]
    names += [f"{arm}_gripper" for arm in plan.arm_names]
    names += [f"{arm}_held" for arm in plan.arm_names]
    return ["time", *names]


def write_csv(plan: PlanFile, path: Path, rate: float = CSV_RATE) -> Path:
    """Write ``plan`` resampled at ``rate`` [1/s] to ``path`` (see the module docstring)."""
    if not (isinstance(rate, int | float) and 0.0 < rate < float("inf")):
        raise ParameterError(f"rate must be a finite number > 0 [1/s], got {rate!r}")
    times = controller_grid(plan.duration, 1.0 / rate)
    q = positions_at(plan, times)
    grip = gripper_states(plan, times)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", encoding="utf-8", newline="") as stream:
        writer = csv.writer(stream, lineterminator="\n")
        writer.writerow(csv_header(plan))
        for k, time in enumerate(times):
            closed = [str(int(c)) for c in grip.closed[k]]
            writer.writerow([f"{time:.6f}", *map(repr, q[k].tolist()), *closed, *grip.held[k]])
    return path
