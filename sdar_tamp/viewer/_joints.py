"""The joint-space panel of the 3-D page: per arm, q and q-dot of its joints against the
scene's limits, on the plan's time axis, with the steps shaded and a cursor at the current time.

Positions are drawn as a fraction of each joint's range (0 = lower, 1 = upper limit) and
velocities as a fraction of each joint's velocity limit, so one pair of dashed lines shows every
limit; the hover text gives the values.
"""

from __future__ import annotations

from collections.abc import Sequence

from sdar_tamp.plan_rules import joint_label
from sdar_tamp.viewer._plotly import JSON, typed_array
from sdar_tamp.viewer._story import JointCurves

#: Joint colours, first joint to last (used in turn past the eighth).
JOINT_COLOURS = (
    "#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#a6761d", "#e6ab02", "#666666"
)  # fmt: skip
#: Shape indices in the panel's layout: the time cursor, then the violation line (if any).
CURSOR_SHAPE = 0
_LIMIT = "#c0392b"


def joint_figure(
    curves: JointCurves,
    arm_names: Sequence[str],
    steps: Sequence[tuple[float, float]],
    violation_t: float | None,
) -> JSON:
    """The panel as a plotly figure: two stacked plots per arm (q then q-dot, arm after arm),
    one curve per joint of the arm, named after it; ``x`` holds the times of every curve (a
    typed-array spec), which the curves leave out."""
    rows = [(a, kind) for a in range(len(curves.position)) for kind in ("q", "qd")]
    n = len(rows)
    gap = 0.035
    height = (1.0 - gap * (n - 1)) / n
    data: list[JSON] = []
    layout: JSON = {
        "margin": {"l": 46, "r": 8, "t": 46, "b": 32},
        "paper_bgcolor": "white",
        "plot_bgcolor": "white",
        "showlegend": True,
        "legend": {
            "orientation": "h",
            "x": 0,
            "y": 1.0,
            "yanchor": "bottom",
            "font": {"size": 10},
            "itemwidth": 30,
        },
        "hovermode": "x",
        "font": {"size": 10},
    }
    t = typed_array(curves.t)
    t0, t1 = float(curves.t[0]), float(curves.t[-1])
    shapes: list[JSON] = [_vline(t0, "#222222", "solid", 1.5)]  # the cursor, CURSOR_SHAPE
    if violation_t is not None:
        shapes.append(_vline(violation_t, _LIMIT, "solid", 2))
    shown: set[str] = set()  # joints already in the legend
    for k, (a, kind) in enumerate(rows):
        suffix = "" if k == 0 else str(k + 1)
        top = 1.0 - k * (height + gap)
        values = curves.position[a] if kind == "q" else curves.velocity[a]
        for j in range(values.shape[1]):
            joint = _label(curves, a, j)
            data.append(
                {
                    "type": "scatter",
                    "mode": "lines",
                    "name": joint.replace("_", " "),
                    "legendgroup": joint,
                    "showlegend": joint not in shown,
                    "y": typed_array(values[:, j]),
                    "xaxis": f"x{suffix}",
                    "yaxis": f"y{suffix}",
                    "line": {"color": JOINT_COLOURS[j % len(JOINT_COLOURS)], "width": 1.4},
                    "hovertemplate": "%{y:.2f}<extra>" + joint + "</extra>",
                }
            )
            shown.add(joint)
        label = f"{arm_names[a]} q" if kind == "q" else f"{arm_names[a]} q̇"
        layout[f"yaxis{suffix}"] = {
            "domain": [top - height, top],
            "range": [-0.08, 1.08] if kind == "q" else [-1.15, 1.15],
            "title": {"text": label, "font": {"size": 11}},
            "tickvals": [0, 0.5, 1] if kind == "q" else [-1, 0, 1],
            "ticktext": ["lo", "", "hi"] if kind == "q" else ["-max", "0", "max"],
            "zeroline": False,
            "gridcolor": "#eeeeee",
            "fixedrange": True,
        }
        layout[f"xaxis{suffix}"] = {
            "range": [t0, t1],
            "anchor": f"y{suffix}",
            "matches": "x" if k else None,
            "showticklabels": k == n - 1,
            "title": {"text": "t [s]"} if k == n - 1 else None,
            "gridcolor": "#eeeeee",
            "zeroline": False,
        }
        for y in (0.0, 1.0) if kind == "q" else (-1.0, 1.0):  # the limits
            shapes.append(
                {
                    "type": "line",
                    "xref": f"x{suffix} domain",
                    "yref": f"y{suffix}",
                    "x0": 0,
                    "x1": 1,
                    "y0": y,
                    "y1": y,
                    "line": {"color": _LIMIT, "width": 1, "dash": "dash"},
                }
            )
    for i, (s0, s1) in enumerate(steps):  # steps shaded in turn, across every plot
        if i % 2 == 0:
            shapes.append(
                {
                    "type": "rect",
                    "xref": "x",
                    "yref": "paper",
                    "x0": s0,
                    "x1": s1,
                    "y0": 0,
                    "y1": 1,
                    "fillcolor": "rgba(90,120,160,0.07)",
                    "line": {"width": 0},
                    "layer": "below",
                }
            )
    layout["shapes"] = shapes
    # the times are sent once (``x``); the page gives them to every curve
    return {"data": data, "layout": layout, "x": t}


def _label(curves: JointCurves, arm: int, j: int) -> str:
    """Joint ``j`` of arm ``arm`` as the legend shows it (``shoulder_pan``; ``joint 3`` when
    the curves name no joints)."""
    if arm < len(curves.joints) and j < len(curves.joints[arm]):
        return joint_label(curves.joints[arm][j])
    return f"joint {j + 1}"


def _vline(t: float, colour: str, dash: str, width: float) -> JSON:
    return {"type": "line", "xref": "x", "yref": "paper", "x0": t, "x1": t, "y0": 0, "y1": 1,
            "line": {"color": colour, "width": width, "dash": dash}}  # fmt: skip
