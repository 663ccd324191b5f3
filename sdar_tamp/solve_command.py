"""Former home of ``sdar solve``'s pipeline; the names live in :mod:`sdar_tamp.app` now."""

from __future__ import annotations

from sdar_tamp.app.cache import PlannerCache
from sdar_tamp.app.command import solve_instance
from sdar_tamp.app.records import SolveOutcome
from sdar_tamp.app.summary import ProgressBar, format_summary

__all__ = ["PlannerCache", "ProgressBar", "SolveOutcome", "format_summary", "solve_instance"]
