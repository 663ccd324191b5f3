"""An interactive 3-D page that explains a plan: one self-contained HTML file (plotly, offline).

The page shows the table with the workspace outline, each object's goal as a flat outline in the
object's colour, the objects as boxes and every arm as meshes of their collision shapes; the
fingers close on a grasped object. Under the view, a time slider shows the plan's steps (bands
named by kind, level and objects) and its grasp and release events; buttons play, pause and jump
to the previous or next step, and a menu sets the playback speed. A heads-up line names the
current step and what each arm holds; moving objects are labelled in the view. Beside it, a
joint-space panel draws q and q-dot of each arm against the scene's limits. When the plan breaks
a rule of ``sdar validate``, a banner names the first violation and the slider marks its time.

The page address may end in ``#t=12.5`` (open at 12.5 s) or ``#step=3`` (at the start of the third
step). Arms are sent as link poses per frame (``fps`` frames per second of plan time, interpolated
in the browser) and drawn from one copy of their geometry; plotly.js is embedded gzip-compressed.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np

from sdar_tamp.plan_file import PlanFile
from sdar_tamp.plan_rules import Violation
from sdar_tamp.viewer._geometry import ArmDrawing, box_mesh
from sdar_tamp.viewer._joints import joint_figure
from sdar_tamp.viewer._page import page_html
from sdar_tamp.viewer._plan import PlanLike, StepLike
from sdar_tamp.viewer._plotly import JSON, typed_array
from sdar_tamp.viewer._story import Grip, grips, joint_curves, link_poses, object_holds, pose7
from sdar_tamp.viewer._timeline import Segment, Timeline
from sdar_tamp.viewer.errors import require
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene, load_scene
from sdar_tamp.world.transforms import FloatArray

_log = logging.getLogger(__name__)

#: Object colours, in instance order (matplotlib's tab10).
OBJECT_COLOURS = (
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
    "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf",
)  # fmt: skip
#: Arm colours (first arm, second arm, ...; repeated past the last); grippers and bases are
#: drawn dark grey.
ARM_COLOURS = ("#5b8fd1", "#e08a4f", "#5fb36a", "#a27ccf")
_DARK = "#4d4d4d"
_DIV = "sdar-viewer"
#: Metrics named in the page title when the plan has them.
_TITLE_METRICS = ("actions", "steps", "dual_arm_steps", "planning_time")


def write_html(
    instance: Instance,
    plan: PlanLike | None,
    path: Path,
    scene: Scene | None = None,
    fps: float = 10.0,
    validate: bool = True,
) -> Path:
    """Write the page explaining ``plan`` on ``instance`` to ``path`` (HTML); return the path.

    ``plan`` None draws the scene at the start: objects at their start poses, arms at home.
    ``scene`` gives the robot, table, workspace and joint limits (default: the shipped scene).
    ``fps`` [1/s]: animation frames per second of plan time (the browser interpolates between
    them). ``validate``: replay a :class:`~sdar_tamp.plan_file.PlanFile` with the validator of
    ``sdar validate`` and show its first violation (other plan objects are not validated).
    """
    require("plotly.offline", "the interactive viewer")  # before any work
    scene = scene if scene is not None else load_scene()
    timeline = Timeline.build(instance, plan, scene)
    times = timeline.sample_times(fps) if plan is not None else timeline.t
    violation: Violation | None = None
    validated = validate and isinstance(plan, PlanFile)
    if validated and isinstance(plan, PlanFile):
        from sdar_tamp.replay import validate_plan

        violation = validate_plan(instance, plan, scene).violation
        if violation is not None:
            _log.warning(
                "plan invalid at t=%.3f s: %s: %s (marked in the page)",
                violation.t,
                violation.kind,
                violation.message,
            )
    data = page_data(timeline, scene, times, violation, validated)
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(page_html(str(data["title"]), data), encoding="utf-8")
    return out


def page_data(
    timeline: Timeline,
    scene: Scene,
    times: FloatArray,
    violation: Violation | None = None,
    validated: bool = False,
) -> JSON:
    """Everything the page needs, as JSON-ready values: the 3-D figure at the first frame, the
    joint panel, link poses per frame, holds, steps, events and the verdict of the validator."""
    instance, plan = timeline.instance, timeline.plan
    q = timeline.q_at(times)
    grip = grips(timeline, times)
    # the bases never move: drawn once; the rest of each arm moves by its link poses
    bases = [a.select(a.static_links()) for a in timeline.arms]
    moving = [a.select(a.static_links(), keep=False) for a in timeline.arms]
    poses = [link_poses(a, timeline.arm_q(q, i), grip[i]) for i, a in enumerate(moving)]
    tcps = [a.tcp_poses(timeline.arm_q(q, i)) for i, a in enumerate(timeline.arms)]

    static = [_table(scene), _workspace(scene), *_goal_outlines(instance), _goal_labels(instance)]
    static += [
        _arm_trace(b, f"base {b.name}", b.mesh_vertices(timeline.arm_q(q[:1], i))[0], _DARK)
        for i, b in enumerate(bases)
    ]
    arms = [
        _arm_trace(a, f"arm {a.name}", _posed(a, poses[i][0]), ARM_COLOURS[i % len(ARM_COLOURS)])
        for i, a in enumerate(moving)
    ]
    obj_poses, _ = timeline.object_poses(times[:1])
    obj_local, obj_faces, obj_colours = _object_mesh(instance)
    obj_vertices = np.einsum("bij,bvj->bvi", obj_poses[0, :, :3, :3], obj_local)
    obj_vertices = (obj_vertices + obj_poses[0, :, None, :3, 3]).reshape(-1, 3)
    objects: JSON = {
        "type": "mesh3d",
        "name": "objects",
        **_xyz(obj_vertices),
        **_ijk(obj_faces),
        "facecolor": obj_colours,
        "flatshading": True,
        "text": [o.name for o in instance.objects for _ in range(8)],
        "hoverinfo": "text",
        "lighting": {"ambient": 0.55, "diffuse": 0.7, "specular": 0.1},
    }
    labels: JSON = {
        "type": "scatter3d",
        "mode": "text",
        "name": "labels",
        "x": [],
        "y": [],
        "z": [],
        "text": [],
        "textfont": {"size": 13, "color": "#111111"},
        "hoverinfo": "skip",
        "showlegend": False,
    }
    z_top = max(float(p[..., 2, 3].max()) for p in poses) + 0.12
    figure: JSON = {
        "data": [*static, *arms, objects, labels],
        "layout": _layout(scene, z_top),
    }
    n = len(static)
    steps = timeline.segments() if plan is not None else ()
    names = [a.name for a in timeline.arms]
    return {
        "title": _title(timeline),
        "t0": timeline.t_start,
        "t1": timeline.t_end,
        "times": [round(float(t), 4) for t in times],
        "figure": figure,
        "traces": {
            "arms": list(range(n, n + len(arms))),
            "objects": n + len(arms),
            "labels": n + len(arms) + 1,
        },
        "arms": [_arm_data(a, poses[i], tcps[i], grip[i], i) for i, a in enumerate(moving)],
        "objects": [
            {
                "name": o.name,
                "colour": OBJECT_COLOURS[i % len(OBJECT_COLOURS)],
                "size": list(o.size),
                "holds": [
                    [None if not np.isfinite(t) else round(float(t), 6), arm, _r(pose7(T))]
                    for t, arm, T in holds
                ],
            }
            for i, (o, holds) in enumerate(
                zip(instance.objects, object_holds(timeline), strict=True)
            )
        ],
        "objectLocal": typed_array(obj_local),
        "steps": [
            _step_data(s, plan.steps[k] if plan is not None and k < len(plan.steps) else None)
            for k, s in enumerate(steps)
        ],
        "events": [
            {"t": float(e.t), "arm": names.index(e.arm), "type": e.type, "object": e.object}
            for e in (plan.events if plan is not None else ())
        ],
        "joints": (
            joint_figure(
                joint_curves(timeline, scene),
                names,
                [(s.t_start, s.t_end) for s in steps],
                violation.t if violation is not None else None,
            )
            if plan is not None
            else None
        ),
        "validated": validated,
        "violation": (
            {"t": violation.t, "kind": violation.kind, "message": violation.message}
            if violation is not None
            else None
        ),
    }


def _step_data(segment: Segment, step: StepLike | None) -> JSON:
    return {
        "t_start": segment.t_start,
        "t_end": segment.t_end,
        "label": segment.label,
        "kind": str(step.kind) if step is not None else "",
        "objects": list(step.objects) if step is not None else [],
    }


def _r(values: FloatArray) -> list[float]:
    return [round(float(v), 6) for v in np.asarray(values).reshape(-1)]


def _posed(arm: ArmDrawing, T: FloatArray) -> FloatArray:
    """World vertices ``(m, 3)`` of ``arm``'s mesh with its links at ``T`` ``(L, 4, 4)``."""
    Tv = T[arm.vertex_link]
    out: FloatArray = np.einsum("mij,mj->mi", Tv[:, :3, :3], arm.vertices) + Tv[:, :3, 3]
    return out


def _arm_data(arm: ArmDrawing, poses: FloatArray, tcp: FloatArray, grip: Grip, i: int) -> JSON:
    return {
        "name": arm.name,
        "colour": ARM_COLOURS[i % len(ARM_COLOURS)],
        "links": list(arm.links),
        "local": typed_array(arm.vertices),
        "vlink": typed_array(arm.vertex_link, "i4"),
        "poses": typed_array(pose7(poses)),  # (k, L, 7)
        "tcp": typed_array(pose7(tcp)),  # (k, 7)
        "closure": typed_array(grip.closure),  # (k,)
    }


# -- traces -----------------------------------------------------------------------------------
def _xyz(v: FloatArray) -> JSON:
    return {"x": typed_array(v[:, 0]), "y": typed_array(v[:, 1]), "z": typed_array(v[:, 2])}


def _ijk(f: Any) -> JSON:
    f = np.asarray(f)
    return {"i": typed_array(f[:, 0], "i4"), "j": typed_array(f[:, 1], "i4"),
            "k": typed_array(f[:, 2], "i4")}  # fmt: skip


def _table(scene: Scene) -> JSON:
    sx, sy, sz = scene.table.size
    v, f = box_mesh((sx, sy, sz))
    v = v + np.array([0.0, 0.0, -sz / 2])
    return {"type": "mesh3d", "name": "table", **_xyz(v), **_ijk(f), "color": "#e9dcc3",
            "flatshading": True, "hoverinfo": "skip", "lighting": {"ambient": 0.8}}  # fmt: skip


def _line(xy: list[tuple[float, float]], z: float, colour: str, name: str, width: float) -> JSON:
    pts = [*xy, xy[0]]
    return {
        "type": "scatter3d",
        "mode": "lines",
        "name": name,
        "x": [p[0] for p in pts],
        "y": [p[1] for p in pts],
        "z": [z] * len(pts),
        "line": {"color": colour, "width": width},
        "hoverinfo": "name",
        "showlegend": False,
    }


def _workspace(scene: Scene) -> JSON:
    (x0, x1), (y0, y1) = scene.workspace.x, scene.workspace.y
    return _line([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], 0.0005, "orange", "workspace", 3)


def _goal_outlines(instance: Instance) -> list[JSON]:
    from sdar_tamp.world.footprint import corners

    rects = corners(instance.goal_poses(), instance.sizes()[:, :2])
    return [
        _line(
            [(float(p[0]), float(p[1])) for p in rect],
            0.001,
            OBJECT_COLOURS[i % len(OBJECT_COLOURS)],
            f"goal of {o.name}",
            5,
        )
        for i, (o, rect) in enumerate(zip(instance.objects, rects, strict=True))
    ]


def _goal_labels(instance: Instance) -> JSON:
    goals = instance.goal_poses()
    return {
        "type": "scatter3d",
        "mode": "text",
        "name": "goal labels",
        "x": goals[:, 0].tolist(),
        "y": goals[:, 1].tolist(),
        "z": [0.002] * len(goals),
        "text": list(instance.names),
        "textfont": {"size": 10, "color": "#333333"},
        "hoverinfo": "skip",
        "showlegend": False,
    }


def _object_mesh(instance: Instance) -> tuple[FloatArray, Any, list[str]]:
    local, faces, colours = [], [], []
    for i, o in enumerate(instance.objects):
        v, f = box_mesh(o.size)
        local.append(v)
        faces.append(f + 8 * i)
        colours += [OBJECT_COLOURS[i % len(OBJECT_COLOURS)]] * len(f)
    if not local:
        return np.zeros((0, 8, 3)), np.zeros((0, 3), dtype=np.int64), []
    return np.stack(local), np.vstack(faces), colours


def _arm_trace(arm: ArmDrawing, name: str, vertices: FloatArray, colour: str) -> JSON:
    static = arm.static_links()
    shade = [
        _DARK if s.link.startswith("gripper") or s.link in static else colour for s in arm.shapes
    ]
    return {
        "type": "mesh3d",
        "name": name,
        **_xyz(vertices),
        **_ijk(arm.faces),
        "facecolor": [shade[int(s)] for s in arm.face_shape],
        "flatshading": True,
        "hoverinfo": "name",
        "lighting": {"ambient": 0.5, "diffuse": 0.8, "specular": 0.2, "roughness": 0.6},
    }


# -- layout and controls ----------------------------------------------------------------------
def _title(timeline: Timeline) -> str:
    plan = timeline.plan
    name = timeline.instance.name
    if plan is None:
        return f"{name}: start (arms at home)"
    parts = [f"{name}: {timeline.t_end - timeline.t_start:.1f} s"]
    if len(plan.steps) > 0 and plan.metrics.steps is None:
        parts.append(f"{len(plan.steps)} steps")
    numbers = {
        key: value
        for key, value in plan.metrics.as_json().items()
        if isinstance(value, (int, float)) and not isinstance(value, bool)
    }
    keys = [k for k in _TITLE_METRICS if k in numbers] or list(numbers)[:4]
    for key in keys:
        unit = " s" if key.endswith("_time") else ""
        parts.append(f"{key.replace('_', ' ')} {numbers[key]:.3g}{unit}")
    return ", ".join(parts)


def _layout(scene: Scene, z_top: float) -> JSON:
    sx, sy, _ = scene.table.size
    bases = np.array([a.T_world_base[:2, 3] for a in scene.arms]).reshape(-1, 2)
    # the table, and every arm's base with room around it (bases may stand past the table)
    xr = (min(-sx / 2, float(bases[:, 0].min()) - 0.1) - 0.05,
          max(sx / 2, float(bases[:, 0].max()) + 0.1) + 0.05)  # fmt: skip
    yr = (min(-sy / 2, float(bases[:, 1].min()) - 0.1) - 0.05,
          max(sy / 2, float(bases[:, 1].max()) + 0.1) + 0.05)  # fmt: skip
    zr = (-0.06, z_top)
    span = xr[1] - xr[0]

    def axis(title: str, r: tuple[float, float]) -> JSON:
        return {
            "title": {"text": title},
            "range": list(r),
            "autorange": False,
            "backgroundcolor": "#f7f7f7",
            "gridcolor": "#dddddd",
            "zeroline": False,
        }

    return {
        "margin": {"l": 0, "r": 0, "t": 0, "b": 0},
        "paper_bgcolor": "white",
        "showlegend": False,
        "uirevision": "sdar",
        "scene": {
            "xaxis": axis("x [m]", xr),
            "yaxis": axis("y [m]", yr),
            "zaxis": axis("z [m]", zr),
            "aspectmode": "manual",
            "aspectratio": {"x": 1.0, "y": (yr[1] - yr[0]) / span, "z": (zr[1] - zr[0]) / span},
            "camera": {
                "eye": {"x": 0.28, "y": -1.08, "z": 0.62},
                "center": {"x": 0, "y": 0, "z": -0.12},
            },
            "domain": {"x": [0, 1], "y": [0, 1]},
        },
    }
