"""The records of a streamed plan (``sdar solve --stream``): one JSON object per line.

A stream is a header, one record per planned step, and an end record (``"type"``:
``"header"``, ``"step"``, ``"end"``). Their ``trajectory``, ``events`` and ``steps`` are the
plan file's (:mod:`sdar_tamp.plan_file`: absolute times [s], the arms' joints in ``arms``
order), cut where each step was planned: the trajectories of the records, concatenated in
order, are the plan file's trajectory (each record's samples come after the last one's), and
likewise its events and motion segments. A step's trajectory holds every sample fixed when the
step was planned: its motions up to its last gripper events; the dwell after those events comes
with the next step (or the end record), since the next step's gripper events may join them at
that instant. :func:`plan_from_records` rebuilds the plan file.

::

    {"type": "header", "format": "sdar-plan-stream", "version": 1, "units": {...},
     "instance": "M1", "execution": "sync", "gripper_dwell": 0.5,
     "arms": [... as in the plan file ...], "start_poses": {"o1": [x, y, yaw], ...}}
    {"type": "step", "index": 0, "task": {"kind", "objects", "arms", "to_buffer"},
     "planned_at": 0.31,        # [s] after the stream started: when the step was ready
     "trajectory": {"t": [...], "q": [...]}, "events": [...], "steps": [...]}
    ...
    {"type": "end", "status": "solved", "valid": true, "violation": null,
     "trajectory": {...}, "events": [], "steps": [], "final_poses": {...}, "metrics": {...}}
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

from sdar_tamp.errors import ParameterError
from sdar_tamp.plan_building import PlanPart
from sdar_tamp.plan_file import UNITS, VERSION, ArmInfo, PlanFile
from sdar_tamp.plan_reading import plan_from_dict
from sdar_tamp.plan_writing import json_value, plan_to_dict

STREAM_FORMAT = "sdar-plan-stream"
STREAM_VERSION = 1
Pose3 = tuple[float, float, float]


@dataclass(frozen=True)
class StreamHeader:
    """What a consumer needs before the first step: the instance, the arms (names, joint
    names, frames, home), the objects' start poses ``(x, y, yaw)`` [m, m, rad], the dwell [s]
    after gripper events and the execution timing (``"sync"``)."""

    instance: str
    arms: tuple[ArmInfo, ...]
    start_poses: Mapping[str, Pose3]
    gripper_dwell: float
    execution: str = "sync"


@dataclass(frozen=True)
class StreamStep:
    """One planned and checked step: the task (kind, objects, arms, moves to buffers), when
    it was ready (``planned_at`` [s] after the stream started) and its part of the plan."""

    index: int
    kind: str
    objects: tuple[str, ...]
    arms: tuple[str, ...]
    to_buffer: tuple[bool, ...]
    planned_at: float
    part: PlanPart


def _part_dict(part: PlanPart) -> dict[str, Any]:
    """``trajectory``, ``events`` and ``steps`` of ``part`` as the plan file writes them."""
    return {
        "trajectory": {"t": part.t.tolist(), "q": part.q.tolist()},
        "events": json_value(part.events),
        "steps": json_value(part.steps),
    }


def header_record(header: StreamHeader) -> dict[str, Any]:
    """The JSON object of the stream's first line."""
    return {
        "type": "header",
        "format": STREAM_FORMAT,
        "version": STREAM_VERSION,
        "units": dict(UNITS),
        "instance": header.instance,
        "execution": header.execution,
        "gripper_dwell": header.gripper_dwell,
        "arms": json_value(header.arms),
        "start_poses": {k: list(v) for k, v in header.start_poses.items()},
    }


def step_record(step: StreamStep) -> dict[str, Any]:
    """The JSON object of one step's line."""
    return {
        "type": "step",
        "index": step.index,
        "task": {
            "kind": step.kind,
            "objects": list(step.objects),
            "arms": list(step.arms),
            "to_buffer": list(step.to_buffer),
        },
        "planned_at": step.planned_at,
        **_part_dict(step.part),
    }


def end_record(
    status: str,
    part: PlanPart | None,
    plan: PlanFile | None,
    valid: bool,
    violation: str = "",
    diagnosis: Iterable[str] = (),
) -> dict[str, Any]:
    """The JSON object of the last line: the status, the last part of the plan (the dwell
    after the last gripper events), the plan file's ``final_poses`` and ``metrics``, the
    replay's verdict on the whole plan, and without a plan the diagnosis."""
    record: dict[str, Any] = {"type": "end", "status": status, "valid": valid}
    record["violation"] = violation or None
    if part is not None:
        record.update(_part_dict(part))
    if plan is not None:
        whole = plan_to_dict(plan)
        record["final_poses"] = whole["final_poses"]
        record["metrics"] = whole["metrics"]
    record["diagnosis"] = list(diagnosis)
    return record


def plan_from_records(records: Iterable[Mapping[str, Any]], source: str = "<stream>") -> PlanFile:
    """The plan file of a whole stream (its JSON objects, header first, end last): the parts
    concatenated, read and checked by :func:`~sdar_tamp.plan_reading.plan_from_dict`.

    Raises:
        ParameterError: no header first, a record of an unknown type, no end record, or an
            end record without a plan.
        PlanFileError: the assembled plan is malformed (located by its key).
    """
    items = list(records)
    if not items or items[0].get("type") != "header":
        raise ParameterError(f"{source}: a stream starts with its header record")
    header = items[0]
    if header.get("format") != STREAM_FORMAT or header.get("version") != STREAM_VERSION:
        raise ParameterError(
            f"{source}: expected format {STREAM_FORMAT!r} version {STREAM_VERSION}, got "
            f"{header.get('format')!r} version {header.get('version')!r}"
        )
    t: list[Any] = []
    q: list[Any] = []
    events: list[Any] = []
    steps: list[Any] = []
    end: Mapping[str, Any] | None = None
    for n, record in enumerate(items[1:], start=2):
        kind = record.get("type")
        if kind not in ("step", "end") or end is not None:
            what = "a record after the end record" if end is not None else f"type {kind!r}"
            raise ParameterError(f"{source}: line {n}: unexpected {what}")
        if kind == "end":
            end = record
            if "final_poses" not in record:
                raise ParameterError(f"{source}: line {n}: the stream ended without a plan")
        trajectory = record.get("trajectory", {"t": [], "q": []})
        t.extend(trajectory["t"])
        q.extend(trajectory["q"])
        events.extend(record.get("events", []))
        steps.extend(record.get("steps", []))
    if end is None:
        raise ParameterError(f"{source}: the stream has no end record")
    data = {
        "format": "sdar-plan",
        "version": VERSION,
        "units": header["units"],
        "instance": header["instance"],
        "arms": header["arms"],
        "trajectory": {"t": t, "q": q},
        "events": events,
        "final_poses": end["final_poses"],
        "metrics": end["metrics"],
        "steps": steps,
    }
    return plan_from_dict(data, source)
