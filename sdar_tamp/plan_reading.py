"""Reading plan files: the JSON checked key by key into a :class:`~sdar_tamp.plan_file.PlanFile`.

Every failure is a :class:`~sdar_tamp.plan_file.PlanFileError` naming the file, the line and
column of the value at fault and its key path (``plan.json:40:7: trajectory.q[3]: expected 12
numbers, got 11``); JSON nested deeper than :data:`~sdar_tamp.plan_file.MAX_DEPTH` levels is
refused at its first bracket too deep. Each arm has as many joints as its ``joints`` names; its
``home`` and its share of every ``trajectory.q`` row follow. Given the cell's
:class:`~sdar_tamp.world.layout.ArmLayout`, each arm must have the joint count of the cell's arm
in its place (``plan.json:31:17: arms[1].joints: the cell's arm 'right' has 7 joints, the plan's
arm 'right' 6 (...)``); names and frames are the validator's scene rule.

Both versions of the format are read (:data:`~sdar_tamp.plan_file.READ_VERSIONS`): a version-1
file holds exactly two arms (``plan.json:10:11: arms: expected 2 arms (a version-1 file), got
3``), a version-2 file one or more; the rest of the layout is the same, so a version-1 file
reads into the same :class:`~sdar_tamp.plan_file.PlanFile` as its version-2 copy.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np

from sdar_tamp.errors import SourceLocation
from sdar_tamp.plan_file import (
    EVENT_TYPES,
    FORMAT,
    MAX_DEPTH,
    MAX_DT,
    READ_VERSIONS,
    UNITS,
    ArmInfo,
    PlanEvent,
    PlanFile,
    PlanFileError,
    PlanObservation,
    StepRecord,
)
from sdar_tamp.plan_metrics import MetricValue, PlanMetrics
from sdar_tamp.textfile import read_text
from sdar_tamp.world.layout import ArmLayout
from sdar_tamp.world.transforms import FloatArray


class _Reader:
    """Typed access to parsed JSON values; every failure names the file and the key path."""

    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, key: str, detail: str) -> PlanFileError:
        return PlanFileError(self.source, key, detail)

    def obj(self, v: Any, key: str, required: list[str], optional: tuple[str, ...] = ()) -> Any:
        if not isinstance(v, dict):
            raise self.fail(key, f"expected an object with keys {required}, got {_show(v)}")
        prefix = f"{key}." if key else ""
        for k in required:
            if k not in v:
                raise self.fail(key, f"missing key {k!r}")
        for k in v:
            if k not in required and k not in optional:
                raise self.fail(f"{prefix}{k}", f"unexpected key; expected {required}")
        return v

    def mapping(self, v: Any, key: str, what: str) -> dict[str, Any]:
        if not isinstance(v, dict):
            raise self.fail(key, f"expected an object of {what}, got {_show(v)}")
        return v

    def items(self, v: Any, key: str, n: int | None = None, what: str = "items") -> list[Any]:
        if not isinstance(v, list):
            raise self.fail(key, f"expected a list of {what}, got {_show(v)}")
        if n is not None and len(v) != n:
            raise self.fail(key, f"expected {n} {what}, got {len(v)}")
        return v

    def num(self, v: Any, key: str) -> float:
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise self.fail(key, f"expected a finite number, got {_show(v)}")
        return float(v)

    def text(self, v: Any, key: str) -> str:
        if not isinstance(v, str) or not v:
            raise self.fail(key, f"expected a non-empty string, got {_show(v)}")
        return v

    def vec(self, v: Any, key: str, n: int) -> FloatArray:
        items = self.items(v, key, n, "numbers")
        return np.array([self.num(x, f"{key}[{i}]") for i, x in enumerate(items)])

    def pose(self, v: Any, key: str) -> FloatArray:
        rows = self.items(v, key, 4, "rows of a 4x4 transform")
        T = np.stack([self.vec(r, f"{key}[{i}]", 4) for i, r in enumerate(rows)])
        R = T[:3, :3]
        ok = np.allclose(T[3], [0, 0, 0, 1]) and np.allclose(R.T @ R, np.eye(3), atol=1e-6)
        if not ok or np.linalg.det(R) < 0:
            raise self.fail(key, "expected a rigid transform (rotation, translation; 0 0 0 1)")
        return T


def _show(v: Any) -> str:
    text = json.dumps(v) if not isinstance(v, float) else repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


def load_plan(path: Path, layout: ArmLayout | None = None) -> PlanFile:
    """Read and check a plan file (see the module docstring); ``layout``: the cell's arms, whose
    joint counts the plan's arms must have, in order."""
    path = Path(path)
    text = read_text(path, _file_error)
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        where = f"{path}:{exc.lineno}:{exc.colno}"
        raise PlanFileError(where, "", f"invalid JSON: {exc.msg}") from None
    except RecursionError:
        raise _too_deep(text, str(path)) from None
    except ValueError as exc:  # such as an integer with more digits than Python converts
        raise PlanFileError(str(path), "", f"invalid JSON: {exc}") from None
    if _nesting_exceeds(data, MAX_DEPTH):
        raise _too_deep(text, str(path))
    try:
        return plan_from_dict(data, str(path), layout)
    except PlanFileError as err:
        spot = locate_key(text, err.key) if err.key else None
        if spot is None:
            raise
        raise PlanFileError(f"{path}:{spot[0]}:{spot[1]}", err.key, err.detail) from None


def _file_error(detail: str, file: str, location: SourceLocation | None) -> PlanFileError:
    return PlanFileError(str(location) if location is not None else file, "", detail)


def _nesting_exceeds(data: Any, limit: int) -> bool:
    """Whether lists and objects in ``data`` nest deeper than ``limit`` (without recursion)."""
    if not isinstance(data, dict | list):
        return False
    stack: list[tuple[Any, int]] = [(data, 1)]
    while stack:
        value, depth = stack.pop()
        if depth > limit:
            return True
        children = value.values() if isinstance(value, dict) else value  # only dicts and lists
        stack.extend((child, depth + 1) for child in children if isinstance(child, dict | list))
    return False


_JSON_NESTING = re.compile(r'"(?:[^"\\]|\\.)*"|[\[\]{}]')


def _too_deep(text: str, file: str) -> PlanFileError:
    """The error for JSON nested deeper than :data:`MAX_DEPTH`, at the first bracket too deep."""
    depth = 0
    for match in _JSON_NESTING.finditer(text):
        token = match.group()
        if token in ("[", "{"):
            depth += 1
            if depth > MAX_DEPTH:
                start = match.start()
                line = text.count("\n", 0, start) + 1
                column = start - (text.rfind("\n", 0, start) + 1) + 1
                file = f"{file}:{line}:{column}"
                break
        elif token in ("]", "}"):
            depth -= 1
    return PlanFileError(file, "", f"lists and objects nested deeper than {MAX_DEPTH} levels")


_TOP = ["format", "version", "units", "instance", "arms", "trajectory", "events"]
_TOP += ["final_poses", "metrics"]


def plan_from_dict(data: Any, source: str = "<plan>", layout: ArmLayout | None = None) -> PlanFile:
    """A :class:`PlanFile` from its JSON value; ``source`` names it in error messages;
    ``layout``: the cell's arms, whose joint counts the plan's arms must have, in order."""
    r = _Reader(source)
    top = r.obj(data, "", _TOP, ("steps", "observations"))
    if top["format"] != FORMAT:
        raise r.fail("format", f"expected {FORMAT!r}, got {_show(top['format'])}")
    version = top["version"]
    if isinstance(version, bool) or not isinstance(version, int) or version not in READ_VERSIONS:
        raise r.fail(
            "version",
            f"expected one of {sorted(READ_VERSIONS)} (this reader), got {_show(version)}",
        )
    if top["units"] != UNITS:
        raise r.fail("units", f"expected {json.dumps(UNITS)}, got {_show(top['units'])}")
    items = _arm_items(r, top["arms"], version)
    arms = tuple(_arm(r, a, f"arms[{i}]") for i, a in enumerate(items))
    for i, arm in enumerate(arms):
        if arm.name in (a.name for a in arms[:i]):
            raise r.fail(f"arms[{i}].name", f"expected a name different from {arm.name!r}")
    if layout is not None:
        _match_cell(r, arms, layout)
    own = ArmLayout(tuple(a.name for a in arms), tuple(len(a.home) for a in arms))
    t, q = _trajectory(r, top["trajectory"], own.dof)
    events = _events(r, top["events"], own.names, float(t[-1]))
    final: dict[str, tuple[float, float, float]] = {}
    for name, pose in r.mapping(top["final_poses"], "final_poses", "object poses").items():
        x, y, yaw = r.vec(pose, f"final_poses.{name}", 3)
        final[name] = (float(x), float(y), float(yaw))
    metrics: dict[str, MetricValue] = {}
    for name, value in r.mapping(top["metrics"], "metrics", "metrics").items():
        ok = isinstance(value, str) or (isinstance(value, int) and not isinstance(value, bool))
        metrics[name] = value if ok else r.num(value, f"metrics.{name}")
    steps = tuple(
        _step(r, s, f"steps[{i}]") for i, s in enumerate(r.items(top.get("steps", []), "steps"))
    )
    instance = r.text(top["instance"], "instance")
    seen = tuple(
        _observation(r, o, f"observations[{i}]", float(t[-1]))
        for i, o in enumerate(r.items(top.get("observations", []), "observations"))
    )
    metrics_ = PlanMetrics.from_mapping(metrics)
    return PlanFile(instance, arms, t, q, events, final, metrics_, steps, seen)


def _observation(r: _Reader, v: Any, key: str, t_end: float) -> PlanObservation:
    o = r.obj(v, key, ["t", "resting", "added"])
    t = r.num(o["t"], f"{key}.t")
    if not 0.0 <= t <= t_end:
        raise r.fail(f"{key}.t", f"expected a time within the trajectory [0, {t_end}] s, got {t!r}")
    triples = {}
    for part in ("resting", "added"):
        items = r.mapping(o[part], f"{key}.{part}", "object name -> 3 numbers").items()
        triples[part] = {n: tuple(map(float, r.vec(x, f"{key}.{part}.{n}", 3))) for n, x in items}
    for name, size in triples["added"].items():
        if min(size) <= 0.0:
            raise r.fail(f"{key}.added.{name}", f"expected side lengths > 0 [m], got {list(size)}")
    return PlanObservation(t, triples["resting"], triples["added"])  # type: ignore[arg-type]


def _arm_items(r: _Reader, v: Any, version: int) -> list[Any]:
    """The ``arms`` list, as many as ``version`` allows (version 1: exactly two; 2: one or
    more; :data:`~sdar_tamp.plan_file.READ_VERSIONS`)."""
    low, high = READ_VERSIONS[version]
    items = r.items(v, "arms", what="arms")
    exact = high is not None  # a version allows an exact count, or a minimum
    if len(items) < low or (exact and len(items) != high):
        count = f"{low} arms" if exact else f"at least {low} arm{'s' if low > 1 else ''}"
        raise r.fail("arms", f"expected {count} (a version-{version} file), got {len(items)}")
    return items


def _arm(r: _Reader, v: Any, key: str) -> ArmInfo:
    a = r.obj(v, key, ["name", "joints", "T_world_base", "T_tool0_tcp", "home"])
    joints = r.items(a["joints"], f"{key}.joints", what="joint names")
    if not joints:
        raise r.fail(f"{key}.joints", "expected the arm's joint names, got an empty list")
    return ArmInfo(
        r.text(a["name"], f"{key}.name"),
        tuple(r.text(j, f"{key}.joints[{i}]") for i, j in enumerate(joints)),
        r.pose(a["T_world_base"], f"{key}.T_world_base"),
        r.pose(a["T_tool0_tcp"], f"{key}.T_tool0_tcp"),
        r.vec(a["home"], f"{key}.home", len(joints)),
    )


def _match_cell(r: _Reader, arms: tuple[ArmInfo, ...], layout: ArmLayout) -> None:
    """Every arm of the plan has as many joints as the cell's arm in its place (the names and
    the rest of the arms' frames are the validator's scene rule)."""
    if len(arms) != len(layout):
        raise r.fail("arms", f"the cell has {len(layout)} arms, the plan {len(arms)}")
    for i, (info, name, dof) in enumerate(zip(arms, layout.names, layout.dofs, strict=True)):
        if len(info.joints) != dof:
            raise r.fail(
                f"arms[{i}].joints",
                f"the cell's arm {name!r} has {dof} joints, the plan's arm {info.name!r} "
                f"{len(info.joints)} ({', '.join(info.joints)})",
            )


def _trajectory(r: _Reader, v: Any, dof: int) -> tuple[FloatArray, FloatArray]:
    traj = r.obj(v, "trajectory", ["t", "q"])
    t = np.array(
        [
            r.num(x, f"trajectory.t[{i}]")
            for i, x in enumerate(r.items(traj["t"], "trajectory.t", what="times"))
        ]
    )
    if len(t) == 0:
        raise r.fail("trajectory.t", "expected at least one time, got an empty list")
    rows = r.items(traj["q"], "trajectory.q", len(t), "rows (one per time in trajectory.t)")
    q = np.stack([r.vec(row, f"trajectory.q[{i}]", dof) for i, row in enumerate(rows)])
    if t[0] != 0.0:
        raise r.fail("trajectory.t[0]", f"expected 0, got {t[0]!r}")
    for i in range(1, len(t)):
        h = t[i] - t[i - 1]
        if h <= 0.0:
            raise r.fail(f"trajectory.t[{i}]", f"expected a time > {t[i - 1]!r}, got {t[i]!r}")
        if h > MAX_DT + 1e-9:
            raise r.fail(
                f"trajectory.t[{i}]",
                f"expected at most {MAX_DT} s after trajectory.t[{i - 1}], got {h:.6g} s",
            )
    return t, q


def _events(r: _Reader, v: Any, arms: tuple[str, ...], t_end: float) -> tuple[PlanEvent, ...]:
    out: list[PlanEvent] = []
    for i, item in enumerate(r.items(v, "events", what="events")):
        key = f"events[{i}]"
        e = r.obj(item, key, ["t", "arm", "type", "object", "T_tcp_object"])
        t = r.num(e["t"], f"{key}.t")
        if not 0.0 <= t <= t_end:
            raise r.fail(
                f"{key}.t", f"expected a time within the trajectory [0, {t_end}] s, got {t!r}"
            )
        if out and t < out[-1].t:
            raise r.fail(
                f"{key}.t",
                f"expected a time >= events[{i - 1}].t = {out[-1].t!r} "
                f"(events sorted by time), got {t!r}",
            )
        if e["arm"] not in arms:
            raise r.fail(f"{key}.arm", f"expected one of {list(arms)}, got {_show(e['arm'])}")
        if e["type"] not in EVENT_TYPES:
            raise r.fail(
                f"{key}.type", f"expected one of {list(EVENT_TYPES)}, got {_show(e['type'])}"
            )
        obj = r.text(e["object"], f"{key}.object")
        out.append(
            PlanEvent(t, e["arm"], e["type"], obj, r.pose(e["T_tcp_object"], f"{key}.T_tcp_object"))
        )
    return tuple(out)


def _step(r: _Reader, v: Any, key: str) -> StepRecord:
    s = r.obj(v, key, ["t_start", "t_end", "level", "objects", "kind"])
    objects = r.items(s["objects"], f"{key}.objects", what="object names")
    for k in ("level", "kind"):
        if not isinstance(s[k], str):
            raise r.fail(f"{key}.{k}", f"expected a string, got {_show(s[k])}")
    return StepRecord(
        r.num(s["t_start"], f"{key}.t_start"),
        r.num(s["t_end"], f"{key}.t_end"),
        s["level"],
        tuple(r.text(o, f"{key}.objects[{i}]") for i, o in enumerate(objects)),
        s["kind"],
    )


_JSON_TOKEN = re.compile(r'"(?:[^"\\]|\\.)*"|[\[\]{}:,]|[^\s\[\]{}:,"]+')
_KEY_PART = re.compile(r"\[(\d+)\]|\.?([^.\[\]]+)")


def _key_parts(key: str) -> list[str | int] | None:
    """``arms[1].joints`` as ``["arms", 1, "joints"]`` (None when ``key`` does not parse)."""
    parts: list[str | int] = []
    end = 0
    for m in _KEY_PART.finditer(key):
        if m.start() != end:
            return None
        parts.append(int(m.group(1)) if m.group(1) is not None else m.group(2))
        end = m.end()
    return parts if end == len(key) else None


def locate_key(text: str, key: str) -> tuple[int, int] | None:
    """Line and column (from 1) where the value at the key path ``key`` (as in
    :class:`~sdar_tamp.plan_file.PlanFileError`) starts in the JSON ``text``; None when the
    path is not there (a missing key) or names an object key holding ``.``, ``[`` or ``]``."""
    target = _key_parts(key)
    if target is None:
        return None
    frames: list[list[Any]] = []  # [is_object, key or index, awaiting a key]
    for m in _JSON_TOKEN.finditer(text):
        token = m.group()
        top = frames[-1] if frames else None
        if top is not None and top[0] and top[2]:
            if token.startswith('"'):
                top[1], top[2] = json.loads(token), False
            elif token == "}":
                frames.pop()
            continue
        if token == ":":
            continue
        if token == ",":
            if top is not None:
                if top[0]:
                    top[2] = True
                else:
                    top[1] += 1
            continue
        if token in ("]", "}"):
            frames.pop()
            continue
        if [f[1] for f in frames] == target:
            start = m.start()
            line = text.count("\n", 0, start) + 1
            return line, start - (text.rfind("\n", 0, start) + 1) + 1
        if token == "[":
            frames.append([False, 0, False])
        elif token == "{":
            frames.append([True, None, True])
    return None
