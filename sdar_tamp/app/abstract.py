"""What the task planner alone says about an instance: its geometry-free run on the
instance's dependency graph (actions, buffer moves, steps), which compares SDAR-T with the
baseline independently of motion failures."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from sdar_tamp.app.config import TASK_PLANNERS, check_choice
from sdar_tamp.errors import ParameterError
from sdar_tamp.logs import get_logger
from sdar_tamp.world.dependency import instance_dependency_graph
from sdar_tamp.world.instance import load_instance
from sdar_tamp.world.scene import load_scene
from solvers.sdar.abstract import AbstractRunError, run_abstract
from solvers.sdar.planners import make_task_planner

LOG = get_logger(__name__)


@dataclass(frozen=True)
class AbstractFigures:
    """Counts of a geometry-free run; all None when the task planner failed on the graph."""

    actions: int | None
    buffer_moves: int | None
    steps: int | None


def abstract_figures(
    instance_path: Path, task_planner: str, arms: int | None = None
) -> AbstractFigures:
    """The geometry-free run of ``task_planner`` on the instance in ``instance_path`` for a
    cell of ``arms`` arms (default: the arms of the instance's scene, or of the default
    scene)."""
    check_choice("task_planner", task_planner, TASK_PLANNERS)
    instance = load_instance(instance_path)
    graph = instance_dependency_graph(instance)
    if arms is None:
        arms = len(load_scene(instance.scene_path(instance_path)).arms)
    if arms < 1:
        raise ParameterError(f"arms must be None or >= 1, got {arms}")
    try:
        run = run_abstract(make_task_planner(task_planner), graph, arms=arms)
    except AbstractRunError as error:
        LOG.warning("%s: abstract %s run failed: %s", instance_path.stem, task_planner, error)
        return AbstractFigures(None, None, None)
    return AbstractFigures(run.actions, run.buffer_moves, len(run.steps))
