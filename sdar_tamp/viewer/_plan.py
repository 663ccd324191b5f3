"""The parts of a timed plan the viewer reads, as structural types.

:class:`sdar_tamp.plan_file.PlanFile` satisfies :class:`PlanLike`; so does any object with the
same attributes, which keeps the viewer usable on plans built in memory.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

from numpy.typing import ArrayLike

from sdar_tamp.plan_metrics import PlanMetrics


class ArmLike(Protocol):
    """One arm of a plan: its name, base pose and tool-centre-point offset."""

    @property
    def name(self) -> str: ...
    @property
    def T_world_base(self) -> ArrayLike: ...  # (4, 4)
    @property
    def T_tool0_tcp(self) -> ArrayLike: ...  # (4, 4)


class EventLike(Protocol):
    """A gripper event: ``type`` is ``"grasp"`` or ``"release"``."""

    @property
    def t(self) -> float: ...  # [s]
    @property
    def arm(self) -> str: ...
    @property
    def type(self) -> str: ...
    @property
    def object(self) -> str: ...
    @property
    def T_tcp_object(self) -> ArrayLike: ...  # (4, 4)


class StepLike(Protocol):
    """One synchronous step of the plan."""

    @property
    def t_start(self) -> float: ...  # [s]
    @property
    def t_end(self) -> float: ...  # [s]
    @property
    def level(self) -> str: ...
    @property
    def objects(self) -> Sequence[str]: ...
    @property
    def kind(self) -> str: ...


class PlanLike(Protocol):
    """A timed plan: ``t`` ``(n,)`` [s], ``q`` ``(n, dof)`` [rad] (the arms' joints in
    ``arms`` order)."""

    @property
    def instance(self) -> str: ...
    @property
    def arms(self) -> Sequence[ArmLike]: ...
    @property
    def t(self) -> ArrayLike: ...
    @property
    def q(self) -> ArrayLike: ...
    @property
    def events(self) -> Sequence[EventLike]: ...
    @property
    def metrics(self) -> PlanMetrics: ...
    @property
    def steps(self) -> Sequence[StepLike]: ...
