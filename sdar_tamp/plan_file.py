"""The plan file: one timed dual-arm trajectory with gripper events, as self-describing JSON.

Layout (``version`` 1; every length in m, angle in rad, time in s)::

    {"format": "sdar-plan", "version": 1, "units": {"length": "m", "angle": "rad", "time": "s"},
     "instance": "M1",
     "arms": [{"name", "joints" (6 URDF joint names), "T_world_base" (4x4, the URDF base_link),
               "T_tool0_tcp" (4x4), "home" (6)}, ...two arms, scene order],
     "trajectory": {"t": [n times from 0, spacing <= 0.02], "q": [n rows of 12: arm 1, arm 2]},
     "events": [{"t", "arm", "type": "grasp" | "release", "object", "T_tcp_object" (4x4)}],
                # after its gripper event an arm stands still GRIPPER_DWELL (0.5 s)
     "final_poses": {"o1": [x, y, yaw]},
     "metrics": {"actions", "steps", "dual_arm_steps", "execution_time", "planning_time", ...},
     "steps": [{"t_start", "t_end", "level", "objects", "kind"}]}   # optional

:func:`load_plan` checks the shape of everything and raises :class:`PlanFileError` naming the
file and the key path (``plan.json: trajectory.q[3]: expected 12 numbers, got 11``). Values
holding arrays compare by identity (their arrays are read-only copies); compare
:func:`plan_to_dict` outputs for equality. :func:`build_plan_file` assembles a plan from motion
segments and gripper events.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields, is_dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sdar_tamp.errors import ParameterError, SdarError, SourceLocation
from sdar_tamp.textfile import read_text
from sdar_tamp.world.layout import ArmLayout
from sdar_tamp.world.scene import Scene
from sdar_tamp.world.transforms import FloatArray

FORMAT = "sdar-plan"
VERSION = 1
UNITS = {"length": "m", "angle": "rad", "time": "s"}
MAX_DT = 0.02  #: largest spacing of trajectory samples [s]
EVENT_TYPES = ("grasp", "release")
MAX_DEPTH = 64  #: deepest nesting of JSON lists and objects a plan file may have
#: After its gripper event an arm stands still this long [s] (the gripper closes or opens;
#: the 2F-85 takes about half a second). :func:`build_plan_file` keeps both arms still.
GRIPPER_DWELL = 0.5
#: Arms of a version-1 plan file, and joints per arm (the in-memory plan goes by its layout).
FILE_ARMS = 2
FILE_ARM_JOINTS = 6


def plan_joint_names(arm: str, robot_joints: Sequence[str]) -> tuple[str, ...]:
    """The names in ``arms[].joints``: the arm's name, ``_``, the robot's (URDF) joint name."""
    return tuple(f"{arm}_{j}" for j in robot_joints)


class PlanFileError(SdarError):
    """A malformed plan file; ``file``, ``key`` (JSON key path) and ``detail`` are kept."""

    def __init__(self, file: str, key: str, detail: str) -> None:
        self.file, self.key, self.detail = file, key, detail
        super().__init__(f"{file}: {key}: {detail}" if key else f"{file}: {detail}")


def readonly(value: Any) -> FloatArray:
    """A read-only float64 copy of ``value``."""
    a = np.array(value, dtype=np.float64)
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class ArmInfo:
    """One arm: name, joint names, base and tool frames ``(4, 4)``, home ``(joints,)``
    [rad]."""

    name: str
    joints: tuple[str, ...]
    T_world_base: FloatArray
    T_tool0_tcp: FloatArray
    home: FloatArray

    def __post_init__(self) -> None:
        for key in ("T_world_base", "T_tool0_tcp", "home"):
            object.__setattr__(self, key, readonly(getattr(self, key)))


@dataclass(frozen=True, eq=False)
class PlanEvent:
    """A gripper closing (``grasp``) or opening (``release``) at time ``t`` [s].

    ``T_tcp_object`` ``(4, 4)``: the object's pose in the tool-centre-point frame."""

    t: float
    arm: str
    type: str
    object: str
    T_tcp_object: FloatArray

    def __post_init__(self) -> None:
        object.__setattr__(self, "T_tcp_object", readonly(self.T_tcp_object))


@dataclass(frozen=True)
class StepRecord:
    """One synchronous motion segment ``[t_start, t_end]`` [s] (information for viewers)."""

    t_start: float
    t_end: float
    level: str
    objects: tuple[str, ...]
    kind: str


@dataclass(frozen=True, eq=False)
class PlanFile:
    """A timed plan: samples ``q`` ``(n, layout.dof)`` [rad] at ``t`` ``(n,)`` [s] (the arms'
    joints in ``arms`` order), gripper events, final object poses ``name -> (x, y, yaw)``
    [m, m, rad] and metrics."""

    instance: str
    arms: tuple[ArmInfo, ...]
    t: FloatArray
    q: FloatArray
    events: tuple[PlanEvent, ...]
    final_poses: dict[str, tuple[float, float, float]]
    metrics: dict[str, float | int | str]
    steps: tuple[StepRecord, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "t", readonly(self.t))
        object.__setattr__(self, "q", readonly(self.q))

    @property
    def duration(self) -> float:
        """Time of the last sample [s]."""
        return float(self.t[-1])

    @property
    def arm_names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.arms)

    @property
    def layout(self) -> ArmLayout:
        """The arms' joints in ``q``, each arm as many as its home configuration has (raises
        :class:`ArmLayoutError` for repeated names)."""
        return ArmLayout(self.arm_names, tuple(len(a.home) for a in self.arms))


# -- writing ----------------------------------------------------------------------------------
def plan_to_dict(plan: PlanFile) -> dict[str, Any]:
    """The JSON value of ``plan`` (plain lists, dicts, numbers and strings)."""
    return {
        "format": FORMAT,
        "version": VERSION,
        "units": dict(UNITS),
        "instance": plan.instance,
        "arms": _json(plan.arms),
        "trajectory": {"t": plan.t.tolist(), "q": plan.q.tolist()},
        "events": _json(plan.events),
        "final_poses": _json(plan.final_poses),
        "metrics": dict(plan.metrics),
        "steps": _json(plan.steps),
    }


def _json(value: Any) -> Any:
    """Dataclasses as objects (field order), arrays and tuples as lists, numpy scalars as
    Python numbers."""
    if isinstance(value, np.ndarray | np.generic):
        return value.tolist()
    if is_dataclass(value):
        return {f.name: _json(getattr(value, f.name)) for f in fields(value)}
    if isinstance(value, dict):
        return {k: _json(v) for k, v in value.items()}
    if isinstance(value, tuple | list):
        return [_json(v) for v in value]
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


# -- reading ----------------------------------------------------------------------------------
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


def load_plan(path: Path) -> PlanFile:
    """Read and check a plan file (see the module docstring)."""
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
    return plan_from_dict(data, str(path))


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


def plan_from_dict(data: Any, source: str = "<plan>") -> PlanFile:
    """A :class:`PlanFile` from its JSON value; ``source`` names it in error messages."""
    r = _Reader(source)
    top = r.obj(data, "", _TOP, ("steps",))
    if top["format"] != FORMAT:
        raise r.fail("format", f"expected {FORMAT!r}, got {_show(top['format'])}")
    if top["version"] != VERSION or isinstance(top["version"], bool):
        raise r.fail("version", f"expected {VERSION} (this reader), got {_show(top['version'])}")
    if top["units"] != UNITS:
        raise r.fail("units", f"expected {json.dumps(UNITS)}, got {_show(top['units'])}")
    items = r.items(top["arms"], "arms", FILE_ARMS)
    arms = tuple(_arm(r, a, f"arms[{i}]") for i, a in enumerate(items))
    for i, arm in enumerate(arms):
        if arm.name in (a.name for a in arms[:i]):
            raise r.fail(f"arms[{i}].name", f"expected a name different from {arm.name!r}")
    layout = ArmLayout(tuple(a.name for a in arms), tuple(len(a.home) for a in arms))
    t, q = _trajectory(r, top["trajectory"], layout.dof)
    events = _events(r, top["events"], layout.names, float(t[-1]))
    final: dict[str, tuple[float, float, float]] = {}
    for name, pose in r.mapping(top["final_poses"], "final_poses", "object poses").items():
        x, y, yaw = r.vec(pose, f"final_poses.{name}", 3)
        final[name] = (float(x), float(y), float(yaw))
    metrics: dict[str, float | int | str] = {}
    for name, value in r.mapping(top["metrics"], "metrics", "metrics").items():
        ok = isinstance(value, str) or (isinstance(value, int) and not isinstance(value, bool))
        metrics[name] = value if ok else r.num(value, f"metrics.{name}")
    steps = tuple(
        _step(r, s, f"steps[{i}]") for i, s in enumerate(r.items(top.get("steps", []), "steps"))
    )
    instance = r.text(top["instance"], "instance")
    return PlanFile(instance, arms, t, q, events, final, metrics, steps)


def _arm(r: _Reader, v: Any, key: str) -> ArmInfo:
    a = r.obj(v, key, ["name", "joints", "T_world_base", "T_tool0_tcp", "home"])
    joints = r.items(a["joints"], f"{key}.joints", FILE_ARM_JOINTS, "joint names")
    return ArmInfo(
        r.text(a["name"], f"{key}.name"),
        tuple(r.text(j, f"{key}.joints[{i}]") for i, j in enumerate(joints)),
        r.pose(a["T_world_base"], f"{key}.T_world_base"),
        r.pose(a["T_tool0_tcp"], f"{key}.T_tool0_tcp"),
        r.vec(a["home"], f"{key}.home", len(joints)),
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


# -- building a plan from segments and gripper events ---------------------------------------
@dataclass(frozen=True, eq=False)
class MotionSegment:
    """One synchronous motion: samples ``q`` ``(m, dof)`` [rad] (every arm, in the scene's
    layout) at ``t`` ``(m,)`` [s] from 0."""

    t: FloatArray
    q: FloatArray
    level: str = ""
    objects: tuple[str, ...] = ()
    kind: str = ""


@dataclass(frozen=True, eq=False)
class GripperEvent:
    """``arm`` closes on (``grasp``) or opens from (``release``) ``object``, held at
    ``T_tcp_object`` ``(4, 4)`` in the tool-centre-point frame."""

    arm: str
    type: str
    object: str
    T_tcp_object: FloatArray


#: Metrics computed by :func:`build_plan_file` (they replace values passed under these keys).
COMPUTED_METRICS = ("actions", "steps", "dual_arm_steps", "execution_time")
Pose3 = tuple[float, float, float]


def build_plan_file(
    scene: Scene,
    instance_name: str,
    start_poses: Mapping[str, Pose3],
    sizes: Mapping[str, tuple[float, float, float]],
    items: Sequence[MotionSegment | GripperEvent],
    metrics: Mapping[str, float | int | str],
    gripper_time: float = GRIPPER_DWELL,
    dt: float = MAX_DT,
    q_start: FloatArray | None = None,
) -> PlanFile:
    """Concatenate ``items`` into one timeline (arms in scene order).

    Each segment must start where the timeline stands. Consecutive gripper events (no motion
    between them) of different arms happen at the same instant, followed by one dwell of
    ``gripper_time`` [s] with the robot still; a second event of one arm waits for the dwell
    of its first. The timeline is resampled linearly wherever the spacing exceeds
    ``dt`` [s]. ``final_poses``: start poses ``(x, y, yaw)`` [m, m, rad] of the objects in
    ``start_poses`` (``sizes`` must name the same objects), updated at every release from the
    tool pose (``T_world_tcp @ T_tcp_object`` projected on the table). Metrics: see
    :data:`COMPUTED_METRICS`; other entries of ``metrics`` are passed through. The timeline
    starts at ``q_start`` ``(dof,)``, else at the first segment's start, else at home.
    """
    from sdar_tamp.world.kinematics import ArmKinematics  # pinocchio: imported on use

    if set(sizes) != set(start_poses):
        raise ParameterError(
            f"sizes: expected the objects {sorted(start_poses)}, got {sorted(sizes)}"
        )
    if gripper_time < 0.0 or dt <= 0.0:
        raise ParameterError(f"gripper_time >= 0 and dt > 0 expected [s], got {gripper_time}, {dt}")
    layout = scene.layout
    names = layout.names
    kins = {a: ArmKinematics.from_scene(scene, a) for a in names}
    first = next((i for i in items if isinstance(i, MotionSegment)), None)
    home = scene.home
    q_now = np.array(q_start if q_start is not None else first.q[0] if first else home, float)
    ts: list[FloatArray] = [np.zeros(1)]
    qs: list[FloatArray] = [q_now[None]]
    now, dwell = 0.0, False
    acting: set[str] = set()  # arms whose gripper acts at ``now`` (their dwell not yet over)
    events: list[PlanEvent] = []
    steps: list[StepRecord] = []
    final: dict[str, Pose3] = {
        k: (float(v[0]), float(v[1]), float(v[2])) for k, v in start_poses.items()
    }
    held: dict[str, str] = {}
    actions = dual = 0
    for n, item in enumerate(items):
        if isinstance(item, GripperEvent):
            if item.arm not in names or item.type not in EVENT_TYPES or item.object not in final:
                raise ParameterError(
                    f"items[{n}]: expected an arm of {list(names)}, a type of "
                    f"{list(EVENT_TYPES)} and a known object, got {item}"
                )
            if item.arm in acting and gripper_time > 0.0:  # the arm's previous dwell first
                now += gripper_time
                ts.append(np.array([now]))
                qs.append(q_now[None])
                acting.clear()
            events.append(PlanEvent(now, item.arm, item.type, item.object, item.T_tcp_object))
            acting.add(item.arm)
            dwell = True
            if item.type == "grasp":
                held[item.arm] = item.object
                continue
            actions += held.pop(item.arm, None) == item.object
            q_arm = layout.part(q_now, item.arm)
            T = kins[item.arm].fk_tcp(q_arm) @ np.asarray(item.T_tcp_object)
            final[item.object] = (float(T[0, 3]), float(T[1, 3]), math.atan2(T[1, 0], T[0, 0]))
            continue
        if dwell and gripper_time > 0.0:
            now += gripper_time
            ts.append(np.array([now]))
            qs.append(q_now[None])
        dwell = False
        acting.clear()
        t, q = np.asarray(item.t, dtype=np.float64), np.asarray(item.q, dtype=np.float64)
        if t.ndim != 1 or q.shape != (len(t), layout.dof) or len(t) == 0 or t[0] != 0.0:
            raise ParameterError(
                f"items[{n}]: expected t (m,) from 0 and q (m, {layout.dof}), got {t.shape} and "
                f"{q.shape}"
            )
        if np.any(np.diff(t) <= 0.0):
            raise ParameterError(f"items[{n}].t: expected strictly increasing times")
        jump = float(np.abs(q[0] - q_now).max())
        if jump > 1e-6:
            raise ParameterError(
                f"items[{n}]: the segment starts {jump:.3g} rad away from where the timeline stands"
            )
        moving = np.abs(np.diff(q, axis=0)) > 1e-9
        arms_moving = np.stack([moving[:, s].any(axis=1) for s in layout.slices], axis=1)
        dual += bool(np.any(arms_moving.sum(axis=1) >= 2))  # two arms or more at once
        steps.append(StepRecord(now, now + float(t[-1]), item.level, item.objects, item.kind))
        ts.append(now + t[1:])
        qs.append(q[1:])
        now += float(t[-1])
        q_now = q[-1].copy()
    if dwell and gripper_time > 0.0:
        ts.append(np.array([now + gripper_time]))
        qs.append(q_now[None])
    t_all, q_all = resample(np.concatenate(ts), np.concatenate(qs), dt)
    out = dict(metrics)
    out.update(
        actions=actions, steps=len(steps), dual_arm_steps=dual, execution_time=float(t_all[-1])
    )
    arms = tuple(
        ArmInfo(
            a.name,
            plan_joint_names(a.name, kins[a.name].robot.joint_names),
            a.T_world_base,
            kins[a.name].T_tool0_tcp,
            np.array(a.home),
        )
        for a in scene.arms
    )
    return PlanFile(instance_name, arms, t_all, q_all, tuple(events), final, out, tuple(steps))


def resample(t: FloatArray, q: FloatArray, dt: float) -> tuple[FloatArray, FloatArray]:
    """Insert linearly interpolated samples where the spacing of ``t`` ``(n,)`` exceeds
    ``dt`` [s]; ``q`` is ``(n, k)``."""
    if len(t) < 2:
        return t, q
    h = np.diff(t)
    n = np.maximum(1, np.ceil(h / dt - 1e-9)).astype(int)
    idx = np.repeat(np.arange(len(h)), n)
    frac = (np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)) / np.repeat(n, n)
    t_new = np.append(t[idx] + frac * h[idx], t[-1])
    q_new = np.concatenate([q[idx] + frac[:, None] * (q[idx + 1] - q[idx]), q[-1:]])
    return t_new, q_new
