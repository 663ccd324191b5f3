"""The paper's evaluation (section V): every planner combination on a suite, CSV, plots, report.

``sdar bench`` runs :func:`~sdar_tamp.evaluation.runner.run_bench` (one CSV row per finished
run, resumable), then :func:`~sdar_tamp.evaluation.plots.write_plots` and
:func:`~sdar_tamp.evaluation.report.write_report` on the output folder. Nothing heavy is
imported here; matplotlib is needed only for the plots.
"""

from __future__ import annotations

from sdar_tamp.evaluation.runner import COMBINATIONS, Combination, parse_combos, run_bench

__all__ = ["COMBINATIONS", "Combination", "parse_combos", "run_bench"]
