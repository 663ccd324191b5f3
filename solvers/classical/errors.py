"""Errors raised by the classical planner."""

from __future__ import annotations

from sdar_tamp.errors import SdarError


class GroundingError(SdarError):
    """The lifted task cannot be grounded (a cost term without a value, unstratified axioms...)."""


class PlanValidationError(SdarError):
    """A plan does not solve its task. Raised by the validator; from :func:`plan` it means a bug."""


class BackendUnavailableError(SdarError):
    """An optional planner backend is not installed, or it failed to run."""
