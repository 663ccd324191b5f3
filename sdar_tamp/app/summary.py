"""How a run is shown to people: a few summary lines and a progress bar."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any, TextIO

from sdar_tamp.app.records import SolveOutcome
from sdar_tamp.plan_metrics import PlanMetrics


def format_summary(outcome: SolveOutcome) -> str:
    """A few lines for people: result, actions, steps, times."""
    f = outcome.figures
    head = f"{outcome.instance.name}: {outcome.status}"
    if outcome.plan is None:
        lines = [head, *(f"  {d}" for d in outcome.diagnosis)]
        if outcome.bound is not None:
            lines.append(f"  execution-time bound {outcome.bound.seconds:.1f} s")
        return "\n".join(lines)
    m = outcome.plan.metrics
    lines = [
        head + (", plan valid" if outcome.valid else f", plan INVALID ({outcome.violation})"),
        f"  actions {m.actions} ({f.buffer_moves} to buffers), synchronous steps "
        f"{m.steps} ({m.dual_arm_steps} with {_together(len(outcome.plan.arms))} moving at once)",
        f"  execution time {float(_given(m.execution_time)):.2f} s"
        + _async_note(m, f.schedule_time),
        *_bound_line(outcome),
        f"  planning time {f.planning_time:.2f} s: selection/IK {f.selection_time:.2f} s, "
        f"motion {f.motion_time:.2f} s (setup {f.setup_time:.2f} s not counted; "
        f"optimiser built in the background, waited for {f.optimiser_wait:.2f} s)",
        f"  per step: median {f.step_time_median:.3f} s (selection "
        f"{f.step_selection_median:.3f} s, motion {f.step_motion_median:.3f} s), "
        f"max {f.step_time_max:.3f} s",
        "  motion levels: " + ", ".join(f"{k} {v}" for k, v in f.levels.items()),
    ]
    return "\n".join(lines)


def summary_record(outcome: SolveOutcome, plan_file: Path | None = None) -> dict[str, Any]:
    """The run as one JSON-ready object (``sdar solve --json``): status, validity, the plan's
    metrics, the run's figures and, without a plan, the diagnosis."""
    f = outcome.figures
    record: dict[str, Any] = {
        "instance": outcome.instance.name,
        "status": outcome.status,
        "valid": outcome.valid,
        "violation": outcome.violation or None,
        "plan_file": None if plan_file is None else str(plan_file),
        "metrics": {} if outcome.plan is None else outcome.plan.metrics.as_json(),
        "figures": {
            "planning_time": f.planning_time,
            "selection_time": f.selection_time,
            "motion_time": f.motion_time,
            "setup_time": f.setup_time,
            "schedule_time": f.schedule_time,
            "step_time_median": f.step_time_median,
            "step_time_max": f.step_time_max,
            "buffer_moves": f.buffer_moves,
            "levels": dict(f.levels),
        },
        "diagnosis": list(outcome.diagnosis),
        "bound": bound_record(outcome),
    }
    return record


def bound_record(outcome: SolveOutcome) -> dict[str, Any] | None:
    """The execution-time bound of ``outcome`` as a JSON-ready object (``None`` without one):
    the bound, its two terms, the arms, whether it is proven, the plan's ratio to it."""
    b = outcome.bound
    if b is None:
        return None
    return {
        "seconds": b.seconds,
        "sum_over_arms": b.total / b.arms,
        "longest_object": b.longest,
        "arms": b.arms,
        "objects": len(b.objects),
        "proven": b.proven,
        "execution_over_bound": outcome.execution_over_bound,
    }


def _bound_line(outcome: SolveOutcome) -> list[str]:
    """``execution 23.1 s, bound 14.2 s (1.63x)``: the plan against the lower bound."""
    b, m = outcome.bound, outcome.plan
    if m is None or m.metrics.execution_time is None:
        return []
    if b is None:
        return ["  bound not computed (an arm without the closed-form IK: not provable)"]
    ratio = outcome.execution_over_bound
    times = "" if ratio is None else f" ({ratio:.2f}x)"
    caveat = "" if b.proven else "; IK branches sampled, not proven"
    return [
        f"  execution {float(m.metrics.execution_time):.1f} s, bound {b.seconds:.1f} s{times}: "
        f"sum c_i / {b.arms} arm(s) {b.total / b.arms:.1f} s, longest object {b.longest:.1f} s"
        f"{caveat}"
    ]


def _given(value: float | None) -> float:
    """A metric every plan the pipeline builds has."""
    if value is None:
        raise KeyError("the plan's metrics lack a figure the summary shows")
    return value


def _async_note(metrics: PlanMetrics, schedule_time: float) -> str:
    """How the asynchronous schedule changed the execution time (empty for a sync run)."""
    if schedule_time <= 0.0:
        return ""
    if metrics.execution != "async":
        return f" (asynchronous schedule not shorter, synchronous kept; {schedule_time:.2f} s)"
    sync = float(_given(metrics.execution_time_sync))
    return f" asynchronous (synchronous {sync:.2f} s; scheduled in {schedule_time:.2f} s)"


class ProgressBar:
    """A ``progress(done, total)`` callback drawing a tqdm bar of the objects at their goals.
    The bar appears at once and its clock ticks every ``tick`` [s] between steps (set-up,
    long steps, validation), so no wait passes silently."""

    def __init__(self, label: str, stream: TextIO = sys.stderr, tick: float = 0.5) -> None:
        import threading

        from tqdm import tqdm

        self.label = label
        self.stream = stream
        self._bar: Any = tqdm(total=None, desc=label, unit="obj", file=stream)
        self._stop = threading.Event()
        self._ticker = threading.Thread(target=self._tick, args=(tick,), daemon=True)
        self._ticker.start()

    def _tick(self, tick: float) -> None:
        while not self._stop.wait(tick):
            self._bar.refresh()

    def __call__(self, done: int, total: int) -> None:
        if self._bar.total != total:
            self._bar.total = total
        self._bar.update(done - self._bar.n)

    def stage(self, text: str) -> None:
        """Name what the run does after planning (shown beside the bar until replaced), so a
        wait with every object placed says what it waits for."""
        self._bar.set_postfix_str(text)

    def close(self) -> None:
        self._stop.set()
        self._ticker.join()
        self._bar.close()


def terminal_progress(label: str, stream: TextIO = sys.stderr) -> ProgressBar | None:
    """A :class:`ProgressBar` on ``stream`` when it is a terminal, else ``None``: a log file
    or a pipe gets the summary lines only, not the bar's redraws."""
    isatty = getattr(stream, "isatty", None)
    return ProgressBar(label, stream) if callable(isatty) and isatty() else None


def _together(arms: int) -> str:
    """What a step counted in ``dual_arm_steps`` moves, worded for the cell's arm count."""
    return "both arms" if arms == 2 else "two arms or more"
