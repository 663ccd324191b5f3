"""The ``metrics`` of a plan file: what the planner and the timeline say about the plan.

:class:`PlanMetrics` names the metrics the program writes; the plan file keeps them under
the same JSON keys (the format allows any further string or number metrics, which are kept in
``extra``). :meth:`PlanMetrics.as_json` is the plan file's ``metrics`` object.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields

MetricValue = float | int | str

_INT, _FLOAT, _STR = "int", "float", "str"


@dataclass(frozen=True)
class PlanMetrics:
    """A plan's metrics; ``None``: not in the plan (a plan file need not have them all).

    Planning figures [s] (``planning_time`` and its ``_selection`` and ``_motion`` parts,
    ``step_time_median``), the run that made it (``task_planner``, ``motion_planner``,
    ``seed``, ``buffer_moves``), the counts and duration [s] of the timeline
    (``actions``, ``steps``, ``dual_arm_steps``: motions with two arms or more moving,
    ``execution_time``; see
    :data:`~sdar_tamp.plan_building.COMPUTED_METRICS`), and for an asynchronous schedule
    ``execution`` (``"async"``) and the synchronous duration ``execution_time_sync`` [s].
    ``extra``: any other metrics, by name."""

    planning_time: float | None = None
    planning_time_selection: float | None = None
    planning_time_motion: float | None = None
    task_planner: str | None = None
    motion_planner: str | None = None
    seed: int | None = None
    step_time_median: float | None = None
    buffer_moves: int | None = None
    actions: int | None = None
    steps: int | None = None
    dual_arm_steps: int | None = None
    execution_time: float | None = None
    execution: str | None = None
    execution_time_sync: float | None = None
    extra: Mapping[str, MetricValue] = field(default_factory=dict)

    @classmethod
    def from_mapping(cls, values: Mapping[str, MetricValue]) -> PlanMetrics:
        """The metrics of ``values`` (JSON key -> value): a known key whose value has its
        field's type goes to that field, anything else to ``extra``."""
        known: dict[str, MetricValue] = {}
        extra: dict[str, MetricValue] = {}
        for key, value in values.items():
            kind = _KINDS.get(key)
            (known if kind is not None and _fits(value, kind) else extra)[key] = value
        return cls(**known, extra=extra)  # type: ignore[arg-type]  # checked by _fits

    def updated(self, values: Mapping[str, MetricValue]) -> PlanMetrics:
        """These metrics with ``values`` added or replacing those of the same keys."""
        return PlanMetrics.from_mapping({**self.as_json(), **values})

    def as_json(self) -> dict[str, MetricValue]:
        """JSON key -> value of the metrics present: the named ones in field order, then
        ``extra``."""
        out: dict[str, MetricValue] = {}
        for name in _KINDS:
            value = getattr(self, name)
            if value is not None:
                out[name] = value
        for key, value in self.extra.items():
            out.setdefault(key, value)
        return out


def _fits(value: MetricValue, kind: str) -> bool:
    if isinstance(value, bool):
        return False
    if kind == _STR:
        return isinstance(value, str)
    if kind == _INT:
        return isinstance(value, int)
    return isinstance(value, int | float)


def _kind(annotation: object) -> str:
    text = str(annotation)
    return _INT if text.startswith("int") else _STR if text.startswith("str") else _FLOAT


#: The named fields (every field but ``extra``) and the type of their values.
_KINDS: dict[str, str] = {f.name: _kind(f.type) for f in fields(PlanMetrics) if f.name != "extra"}
