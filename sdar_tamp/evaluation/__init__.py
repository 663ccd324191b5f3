"""The paper's evaluation (section V): every planner combination on a suite, CSV, plots, report.

``sdar bench`` runs :func:`~sdar_tamp.evaluation.runner.run_bench` (one CSV row per finished
run, resumable), then :func:`~sdar_tamp.evaluation.plots.write_plots` and
:func:`~sdar_tamp.evaluation.report.write_report` on the output folder. The rows and the
combinations sit in :mod:`~sdar_tamp.evaluation.results`, below the runner, the report and
the plots (results <- report <- plots <- runner). Nothing heavy is imported here; matplotlib
is needed only for the plots.
"""

from __future__ import annotations

from sdar_tamp.evaluation.results import COMBINATIONS, Combination, parse_combos
from sdar_tamp.evaluation.runner import run_bench

__all__ = ["COMBINATIONS", "Combination", "parse_combos", "run_bench"]
