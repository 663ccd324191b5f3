"""Writing plan files: a :class:`~sdar_tamp.plan_file.PlanFile` as readable, exact JSON."""

from __future__ import annotations

import json
from dataclasses import fields, is_dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sdar_tamp.plan_file import FORMAT, UNITS, VERSION, PlanFile


def plan_to_dict(plan: PlanFile) -> dict[str, Any]:
    """The JSON value of ``plan`` (plain lists, dicts, numbers and strings)."""
    out = {
        "format": FORMAT,
        "version": VERSION,
        "units": dict(UNITS),
        "instance": plan.instance,
        "arms": json_value(plan.arms),
        "trajectory": {"t": plan.t.tolist(), "q": plan.q.tolist()},
        "events": json_value(plan.events),
        "final_poses": json_value(plan.final_poses),
        "metrics": plan.metrics.as_json(),
        "steps": json_value(plan.steps),
    }
    if plan.observations:
        out["observations"] = json_value(plan.observations)
    return out


def json_value(value: Any) -> Any:
    """Dataclasses as objects (field order), arrays and tuples as lists, numpy scalars as
    Python numbers."""
    if isinstance(value, np.ndarray | np.generic):
        return value.tolist()
    if is_dataclass(value):
        return {f.name: json_value(getattr(value, f.name)) for f in fields(value)}
    if isinstance(value, dict):
        return {k: json_value(v) for k, v in value.items()}
    if isinstance(value, tuple | list):
        return [json_value(v) for v in value]
    return value


def _dump(value: Any, indent: str = "") -> str:
    """Readable JSON: lists of scalars on one line, one row per line for matrices."""
    inner = indent + "  "
    if isinstance(value, dict) and value:
        items = [f"{inner}{json.dumps(k)}: {_dump(v, inner)}" for k, v in value.items()]
        return "{\n" + ",\n".join(items) + "\n" + indent + "}"
    if isinstance(value, list) and value and isinstance(value[0], list | dict):
        return "[\n" + ",\n".join(inner + _dump(v, inner) for v in value) + "\n" + indent + "]"
    return json.dumps(value, allow_nan=False)


def save_plan(plan: PlanFile, path: Path) -> Path:
    """Write ``plan`` as JSON to ``path`` (parent folders are created); floats are exact."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(_dump(plan_to_dict(plan)) + "\n", encoding="utf-8")
    return path
