"""An interactive 3-D replay of a plan as one self-contained HTML page (plotly, offline).

The page shows the table with the workspace outline, each object's goal as a flat outline in the
object's colour, the objects as boxes, and both arms as meshes of their collision shapes (links
and gripper). Play/pause buttons and a time slider drive the animation; the page address may end
in ``#t=12.5`` to open at that time [s]. The arms, drawn from the plan's joint trajectory by
forward kinematics, and the objects are sampled at ``fps`` frames per second of plan time.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from sdar_tamp.viewer._geometry import ArmDrawing, box_mesh
from sdar_tamp.viewer._plan import PlanLike
from sdar_tamp.viewer._plotly import JSON, figure_html, typed_array
from sdar_tamp.viewer._timeline import Timeline
from sdar_tamp.world.instance import Instance
from sdar_tamp.world.scene import Scene, load_scene
from sdar_tamp.world.transforms import FloatArray

#: Object colours, in instance order (matplotlib's tab10).
OBJECT_COLOURS = (
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
    "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf",
)  # fmt: skip
#: Arm colours (first arm, second arm); grippers and bases are drawn dark grey.
ARM_COLOURS = ("#5b8fd1", "#e08a4f")
_DARK = "#4d4d4d"
_DIV = "sdar-viewer"
_STATIC = ("base_link",)
#: Metrics named in the page title when the plan has them.
_TITLE_METRICS = ("actions", "steps", "dual_arm_steps", "planning_time")


def write_html(
    instance: Instance,
    plan: PlanLike | None,
    path: Path,
    scene: Scene | None = None,
    fps: float = 10.0,
) -> Path:
    """Write the replay of ``plan`` on ``instance`` to ``path`` (HTML) and return the path.

    ``plan`` None draws the scene at the start: objects at their start poses, arms at home.
    ``scene`` gives the robot, table and workspace (default: the shipped scene). ``fps``
    [1/s] is the number of animation frames per second of plan time.
    """
    scene = scene if scene is not None else load_scene()
    timeline = Timeline.build(instance, plan, scene)
    times = timeline.sample_times(fps) if plan is not None else timeline.t
    figure = build_figure(timeline, scene, times, fps)
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(figure_html(figure, _DIV, _post_script(times)), encoding="utf-8")
    return out


def build_figure(timeline: Timeline, scene: Scene, times: FloatArray, fps: float) -> JSON:
    """The plotly figure (plain dicts) with one animation frame per entry of ``times`` [s]."""
    instance = timeline.instance
    q = timeline.q_at(times)
    # the bases never move: drawn once, outside the animation frames
    bases = [a.select(_STATIC) for a in timeline.arms]
    moving = [a.select(_STATIC, keep=False) for a in timeline.arms]
    arm_vertices = [a.mesh_vertices(timeline.arm_q(q, i)) for i, a in enumerate(moving)]
    obj_poses, _ = timeline.object_poses(times)
    obj_local, obj_faces, obj_colours = _object_mesh(instance)
    obj_vertices = np.einsum("kbij,bvj->kbvi", obj_poses[..., :3, :3], obj_local)
    obj_vertices = (obj_vertices + obj_poses[:, :, None, :3, 3]).reshape(len(times), -1, 3)

    static = [_table(scene), _workspace(scene), *_goal_outlines(instance), _goal_labels(instance)]
    static += [
        _arm_trace(b, f"base {b.name}", b.mesh_vertices(timeline.arm_q(q[:1], i))[0], _DARK)
        for i, b in enumerate(bases)
    ]
    arms = [
        _arm_trace(a, f"arm {a.name}", arm_vertices[i][0], ARM_COLOURS[i % 2])
        for i, a in enumerate(moving)
    ]
    names = [o.name for o in instance.objects for _ in range(8)]
    objects: JSON = {
        "type": "mesh3d",
        "name": "objects",
        **_xyz(obj_vertices[0]),
        **_ijk(obj_faces),
        "facecolor": obj_colours,
        "flatshading": True,
        "text": names,
        "hoverinfo": "text",
        "lighting": {"ambient": 0.55, "diffuse": 0.7, "specular": 0.1},
    }
    data = [*static, *arms, objects]
    dynamic = [len(static), len(static) + 1, len(static) + 2]
    frames = [
        {
            "name": str(k),
            "traces": dynamic,
            "data": [_xyz(arm_vertices[0][k]), _xyz(arm_vertices[1][k]), _xyz(obj_vertices[k])],
        }
        for k in range(len(times))
    ]
    z_top = max(float(v[..., 2].max()) for v in arm_vertices) + 0.05
    layout = _layout(timeline, scene, times, fps, z_top)
    figure: JSON = {"data": data, "layout": layout}
    if len(times) > 1:
        figure["frames"] = frames
    return figure


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
    shade = [
        _DARK if s.link.startswith("gripper") or s.link == "base_link" else colour
        for s in arm.shapes
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
    if len(plan.steps) > 0 and "steps" not in plan.metrics:
        parts.append(f"{len(plan.steps)} steps")
    numbers = {
        key: value
        for key, value in plan.metrics.items()
        if isinstance(value, (int, float)) and not isinstance(value, bool)
    }
    keys = [k for k in _TITLE_METRICS if k in numbers] or list(numbers)[:4]
    for key in keys:
        unit = " s" if key.endswith("_time") else ""
        parts.append(f"{key.replace('_', ' ')} {numbers[key]:.3g}{unit}")
    return ", ".join(parts)


def _layout(timeline: Timeline, scene: Scene, times: FloatArray, fps: float, z_top: float) -> JSON:
    sx, sy, _ = scene.table.size
    xr, yr, zr = (-sx / 2 - 0.05, sx / 2 + 0.05), (-sy / 2 - 0.05, sy / 2 + 0.05), (-0.06, z_top)
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

    layout: JSON = {
        "title": {"text": _title(timeline), "x": 0.02, "font": {"size": 16}},
        "margin": {"l": 0, "r": 0, "t": 40, "b": 0},
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
                "eye": {"x": 0.3, "y": -1.0, "z": 0.6},
                "center": {"x": 0, "y": 0, "z": -0.15},
            },
            "domain": {"x": [0, 1], "y": [0.09 if len(times) > 1 else 0.0, 1]},
        },
    }
    if len(times) > 1:
        layout["updatemenus"] = [_buttons(fps)]
        layout["sliders"] = [_slider(times)]
    return layout


def _animate(frames: list[str | None] | None, duration: float, redraw: bool = True) -> list[Any]:
    return [
        frames,
        {
            "mode": "immediate",
            "fromcurrent": True,
            "frame": {"duration": duration, "redraw": redraw},
            "transition": {"duration": 0},
        },
    ]


def _buttons(fps: float) -> JSON:
    return {
        "type": "buttons",
        "direction": "left",
        "showactive": False,
        "x": 0.01,
        "y": 0.01,
        "xanchor": "left",
        "yanchor": "bottom",
        "pad": {"r": 8},
        "buttons": [
            {"label": "▶ Play", "method": "animate", "args": _animate(None, 1000.0 / fps)},
            {"label": "❚❚ Pause", "method": "animate", "args": _animate([None], 0, False)},
        ],
    }


def _slider(times: FloatArray) -> JSON:
    return {
        "active": 0,
        "x": 0.17,
        "len": 0.81,
        "y": 0.0,
        "yanchor": "bottom",
        "pad": {"t": 0, "b": 4},
        "ticklen": 0,
        "minorticklen": 0,
        "font": {"color": "rgba(0,0,0,0)"},
        "currentvalue": {"prefix": "t = ", "suffix": " s", "font": {"size": 14, "color": "#222"}},
        "steps": [
            {"label": f"{t:.2f}", "method": "animate", "args": _animate([str(k)], 0)}
            for k, t in enumerate(times)
        ],
    }


def _post_script(times: FloatArray) -> str:
    """Open at ``#t=<seconds>`` when the address asks for it; mark the page as drawn."""
    return (
        "(function(){var gd=document.getElementById('" + _DIV + "');"
        "var times=" + json.dumps([round(float(t), 3) for t in times]) + ";"
        "function done(){document.body.setAttribute('data-sdar-ready',String(times.length));}"
        "var m=/[#&]t=([-0-9.eE]+)/.exec(window.location.hash);"
        "if(!m||times.length<2){done();return;}"
        "var t=parseFloat(m[1]),best=0;"
        "for(var k=1;k<times.length;k++){if(Math.abs(times[k]-t)<Math.abs(times[best]-t))best=k;}"
        "Plotly.animate(gd,[String(best)],{mode:'immediate',frame:{duration:0,redraw:true},"
        "transition:{duration:0}}).then(function(){"
        "document.body.setAttribute('data-sdar-frame',String(best));done();});})();"
    )
