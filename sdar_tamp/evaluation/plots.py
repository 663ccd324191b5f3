"""The paper's evaluation figures (section V) as PNG files, from a benchmark folder.

Uses matplotlib's object API (``Figure``, rendered by Agg), never ``pyplot``: no display and no
global figure state. Every function writes one file and returns its path; a figure without
data says so instead of being left out.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from matplotlib.figure import Figure

from sdar_tamp.evaluation.report import (
    action_counts,
    combinations_in,
    execution_ratios,
    instances_in,
    num,
    step_stats,
    succeeded,
)
from sdar_tamp.evaluation.results import Row, instance_sort_key, load_results, load_steps

#: The paper's family colours (light: SDAR-T, dark: baseline): yellow R, green S, blue D, red M.
FAMILY_COLOURS = {
    "R": ("#f7dc6f", "#b7950b"),
    "S": ("#82e0aa", "#1e8449"),
    "D": ("#85c1e9", "#1f618d"),
    "M": ("#f1948a", "#b03a2e"),
}
OTHER = ("#cccccc", "#666666")


def _colour(family: str, dark: bool = False) -> str:
    return FAMILY_COLOURS.get(family[:1], OTHER)[int(dark)]


def _save(fig: Figure, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return path


def _empty(ax: Any, what: str) -> None:
    ax.text(0.5, 0.5, f"no data: {what}", ha="center", va="center", transform=ax.transAxes)
    ax.set_axis_off()


def plot_action_differences(rows: Sequence[Row], path: Path) -> Path:
    """Geometry-free actions of SDAR-T (light) and the baseline (dark) where they differ."""
    diff = [a for a in action_counts(rows) if a.ours and a.theirs and a.ours[0] != a.theirs[0]]
    fig = Figure(figsize=(max(6.0, 0.6 * len(diff) + 2), 3.5))
    ax = fig.subplots()
    if not diff:
        _empty(ax, "SDAR-T and the baseline take the same number of actions everywhere")
        return _save(fig, path)
    x = list(range(len(diff)))
    for k, dark in enumerate((False, True)):
        values = [(a.theirs if dark else a.ours) or (0, 0, 0) for a in diff]
        ax.bar(
            [i + (k - 0.5) * 0.4 for i in x],
            [v[0] for v in values],
            0.4,
            color=[_colour(a.family, dark) for a in diff],
            edgecolor="black",
            linewidth=0.4,
        )
    ax.set_xticks(x, [a.instance for a in diff])
    ax.set_ylabel("actions")
    ax.set_title("Actions where they differ: SDAR-T (light), baseline (dark)", fontsize="medium")
    return _save(fig, path)


def plot_action_ratio(rows: Sequence[Row], path: Path) -> Path:
    """Baseline / SDAR-T geometry-free action ratio, one box per family."""
    per: dict[str, list[float]] = {}
    for a in action_counts(rows):
        if a.ours and a.theirs and a.ours[0] > 0:
            per.setdefault(a.family, []).append(a.theirs[0] / a.ours[0])
    fig = Figure(figsize=(5.0, 3.5))
    ax = fig.subplots()
    if not per:
        _empty(ax, "no action counts")
        return _save(fig, path)
    families = sorted(per, key=instance_sort_key)
    box = ax.boxplot([per[f] for f in families], patch_artist=True)
    for patch, f in zip(box["boxes"], families, strict=True):
        patch.set_facecolor(_colour(f))
    ax.set_xticks(range(1, len(families) + 1), families)
    ax.axhline(1.0, color="red", linestyle="--", linewidth=1)
    ax.set_ylabel("actions: baseline / SDAR-T")
    ax.set_title("Action ratio by family (geometry-free)")
    return _save(fig, path)


#: Instances up to which the execution times are one bar per instance; beyond (a sweep), one
#: box per family and combination.
MAX_BARS = 60


def plot_execution_times(rows: Sequence[Row], path: Path) -> Path:
    """Execution time per instance and combination; a missing bar is a failure. Over
    :data:`MAX_BARS` instances: the distribution per family and combination instead."""
    combos, names = combinations_in(rows), instances_in(rows)
    if len(names) > MAX_BARS:
        return _plot_execution_boxes(rows, len(names), path)
    fig = Figure(figsize=(max(8.0, 0.7 * len(names) + 2), 4.0))
    ax = fig.subplots()
    width = 0.8 / max(1, len(combos))
    times = {
        (r["instance"], r["combination"]): num(r, "execution_time_s") or 0.0
        for r in rows
        if succeeded(r)
    }
    for k, c in enumerate(combos):
        xs = [i + (k - (len(combos) - 1) / 2) * width for i in range(len(names))]
        ax.bar(
            xs,
            [times.get((n, c.id), 0.0) for n, _, _ in names],
            width,
            label=c.label,
            color=f"C{k}",
        )
    ax.set_xticks(range(len(names)), [n for n, _, _ in names])
    ax.set_ylabel("execution time [s]")
    ax.set_title("Execution time (missing bar: no valid plan)")
    ax.legend(fontsize="small", ncols=min(3, len(combos)))
    return _save(fig, path)


def _plot_execution_boxes(rows: Sequence[Row], instances: int, path: Path) -> Path:
    """Execution times of the successful runs: one box per family and combination."""
    combos = combinations_in(rows)
    families = sorted({r["family"] for r in rows}, key=lambda f: instance_sort_key(f + "0"))
    fig = Figure(figsize=(max(8.0, 0.5 * len(families) * len(combos) + 2), 4.0))
    ax = fig.subplots()
    width = 0.8 / max(1, len(combos))
    handles, labels = [], []
    for k, c in enumerate(combos):
        found = [
            (i, [t for r in rows if r["family"] == f and r["combination"] == c.id
                 and succeeded(r) and (t := num(r, "execution_time_s")) is not None])
            for i, f in enumerate(families)
        ]  # fmt: skip
        found = [(i, times) for i, times in found if times]
        if not found:
            continue
        boxes = ax.boxplot(
            [times for _, times in found],
            positions=[i + (k - (len(combos) - 1) / 2) * width for i, _ in found],
            widths=0.9 * width,
            patch_artist=True,
            showfliers=False,
            manage_ticks=False,
            medianprops={"color": "black"},
        )
        for box in boxes["boxes"]:
            box.set_facecolor(f"C{k}")
        handles.append(boxes["boxes"][0])
        labels.append(c.label)
    if not handles:
        _empty(ax, "no successful run")
        return _save(fig, path)
    ax.set_xticks(range(len(families)), families)
    ax.set_xlabel("family")
    ax.set_ylabel("execution time [s]")
    ax.set_title(f"Execution time of the successful runs ({instances} instances)")
    ax.legend(handles, labels, fontsize="small", ncols=min(3, len(combos)))
    return _save(fig, path)


def plot_execution_ratios(rows: Sequence[Row], path: Path) -> Path:
    """Execution time / SDAR's, per combination, one box per family."""
    others = [c for c in combinations_in(rows) if c.id != "sdar"]
    families = sorted({r["family"] for r in rows}, key=instance_sort_key)
    fig = Figure(figsize=(max(6.0, 1.6 * len(others) + 1), 4.0))
    ax = fig.subplots()
    width = 0.8 / max(1, len(families))
    drawn = False
    for k, fam in enumerate(families):
        data, pos = [], []
        for i, c in enumerate(others):
            values = [x for _, f, x in execution_ratios(rows, c.id) if f == fam]
            if values:
                data.append(values)
                pos.append(i + (k - (len(families) - 1) / 2) * width)
        if data:
            drawn = True
            box = ax.boxplot(
                data, positions=pos, widths=width * 0.9, patch_artist=True, showfliers=False
            )
            for patch in box["boxes"]:
                patch.set_facecolor(_colour(fam))
            for p, values in zip(pos, data, strict=True):
                ax.plot([p] * len(values), values, ".", color=_colour(fam, dark=True))
            ax.plot([], [], "s", color=_colour(fam), label=fam)
    if not drawn:
        _empty(ax, "no instance solved by SDAR and another combination")
        return _save(fig, path)
    ax.set_xticks(range(len(others)), [c.label.replace(" + ", "\n+ ") for c in others])
    ax.set_xlim(-0.5, len(others) - 0.5)
    ax.axhline(1.0, color="red", linestyle="--", linewidth=1)
    ax.set_ylabel("execution time / SDAR's")
    ax.set_title("Execution-time ratio to SDAR")
    ax.legend(fontsize="small")
    return _save(fig, path)


def plot_success(rows: Sequence[Row], path: Path) -> Path:
    """Success rate per combination (solved and valid)."""
    combos = combinations_in(rows)
    fig = Figure(figsize=(max(5.0, 1.3 * len(combos) + 1), 3.5))
    ax = fig.subplots()
    rates = []
    for c in combos:
        mine = [r for r in rows if r["combination"] == c.id]
        rates.append(100 * sum(map(succeeded, mine)) / max(1, len(mine)))
    bars = ax.bar(range(len(combos)), rates, color=[f"C{k}" for k in range(len(combos))])
    ax.bar_label(bars, [f"{r:.0f}%" for r in rates])
    ax.set_xticks(range(len(combos)), [c.label.replace(" + ", "\n+ ") for c in combos])
    ax.set_ylim(0, 110)
    ax.set_ylabel("success rate [%]")
    ax.set_title("Success rate (solved and valid)")
    return _save(fig, path)


def plot_step_times(rows: Sequence[Row], steps: Sequence[Row], path: Path) -> Path:
    """Median planning time per synchronous step, stacked: selection (IK) and motion."""
    stats = step_stats(rows, steps)
    combos = [c for c in combinations_in(rows) if c.id in stats]
    fig = Figure(figsize=(max(5.0, 1.3 * len(combos) + 1), 3.5))
    ax = fig.subplots()
    if not combos:
        _empty(ax, "no successful run")
        return _save(fig, path)
    x = range(len(combos))
    sel = [stats[c.id]["selection_median"] for c in combos]
    mot = [stats[c.id]["motion_median"] for c in combos]
    ax.bar(x, sel, label="selection (IK)", color="#f5b041")
    ax.bar(x, mot, bottom=sel, label="motion", color="#5dade2")
    ax.set_xticks(x, [c.label.replace(" + ", "\n+ ") for c in combos])
    ax.set_ylabel("planning time per step [s]")
    ax.set_title("Planning time per step (medians)")
    ax.legend(fontsize="small")
    return _save(fig, path)


def write_plots(out_dir: Path) -> list[Path]:
    """All figures of ``out_dir``'s CSV files, as PNG files beside them."""
    out = Path(out_dir)
    rows, steps = load_results(out), load_steps(out)
    return [
        plot_action_differences(rows, out / "actions_differences.png"),
        plot_action_ratio(rows, out / "actions_ratio.png"),
        plot_execution_times(rows, out / "execution_time.png"),
        plot_execution_ratios(rows, out / "execution_time_ratio.png"),
        plot_success(rows, out / "success_rate.png"),
        plot_step_times(rows, steps, out / "step_planning_time.png"),
    ]
