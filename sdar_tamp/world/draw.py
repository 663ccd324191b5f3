"""Top-down pictures of an instance: start and goal side by side, with the dependency graph.

In the goal panel the start footprints are drawn as white outlines. In the start panel an arrow
``i -> j`` joins the objects for each dependency edge (i's goal overlaps j's start): black along
chains, one colour per cycle, grey for edges between a cycle and the rest.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from sdar_tamp.world.dependency import instance_dependency_graph
from sdar_tamp.world.footprint import corners
from sdar_tamp.world.instance import Instance

_CYCLE_COLOURS = ("tab:red", "tab:blue", "tab:green", "tab:purple", "tab:orange", "tab:brown")


def draw_instance(instance: Instance, path: Path) -> Path:
    """Render ``instance`` to an image file (format from the suffix, e.g. ``.png``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon

    graph = instance_dependency_graph(instance)
    structure = graph.structure()
    colour: dict[str, str] = {n: "tab:gray" for n in instance.names}
    edge_colour: dict[tuple[str, str], str] = {}
    for k, cycle in enumerate(structure.cycles):
        c = _CYCLE_COLOURS[k % len(_CYCLE_COLOURS)]
        for name in cycle:
            colour[name] = c
    chain_of = {n: k for k, chain in enumerate(structure.chains) for n in chain}
    for a, b in graph.named_edges():
        if colour[a] == colour[b] and colour[a] != "tab:gray":
            edge_colour[(a, b)] = colour[a]
        elif a in chain_of and chain_of.get(b) == chain_of[a]:
            edge_colour[(a, b)] = "black"
        else:
            edge_colour[(a, b)] = "0.6"
    for name in chain_of:
        colour[name] = "khaki"
    for name in structure.independent:
        colour[name] = "lightgreen"

    sizes = instance.sizes()[:, :2]
    start, goal = instance.start_poses(), instance.goal_poses()
    fig, axes = plt.subplots(1, 2, figsize=(10, 5.5))
    ws = instance.workspace
    for ax, poses, title in ((axes[0], start, "start"), (axes[1], goal, "goal")):
        ax.add_patch(_rect_patch(Polygon, ws.x, ws.y))
        if title == "goal":
            for rect in corners(start, sizes):
                ax.add_patch(Polygon(rect, closed=True, facecolor="white", edgecolor="0.5", lw=0.8))
        for name, rect, pose in zip(instance.names, corners(poses, sizes), poses, strict=True):
            ax.add_patch(Polygon(rect, closed=True, facecolor=colour[name], edgecolor="black",
                                 alpha=0.85, lw=1.0))  # fmt: skip
            ax.text(pose[0], pose[1], name, ha="center", va="center", fontsize=7)
        ax.set_title(f"{instance.name}: {title}")
        ax.set_aspect("equal")
        ax.set_xlim(ws.x[0] - 0.03, ws.x[1] + 0.03)
        ax.set_ylim(ws.y[0] - 0.03, ws.y[1] + 0.03)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
    index = {n: i for i, n in enumerate(instance.names)}
    for (a, b), c in edge_colour.items():
        p, q = start[index[a], :2], start[index[b], :2]
        axes[0].annotate("", xy=tuple(q), xytext=tuple(p), arrowprops={
            "arrowstyle": "-|>", "color": c, "lw": 1.6, "connectionstyle": "arc3,rad=0.15",
            "shrinkA": 6, "shrinkB": 6})  # fmt: skip
    fig.suptitle(
        f"{len(structure.independent)} independent, {len(structure.chains)} chains, "
        f"{len(structure.cycles)} cycles"
    )
    fig.tight_layout()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out


def _rect_patch(polygon: Any, x: tuple[float, float], y: tuple[float, float]) -> Any:
    pts = [(x[0], y[0]), (x[1], y[0]), (x[1], y[1]), (x[0], y[1])]
    return polygon(pts, closed=True, facecolor="whitesmoke", edgecolor="orange", lw=1.5)
