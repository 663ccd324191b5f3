"""``pddlstream.algorithms.visualization``: where PDDLStream writes its pictures.

Graph drawing (``visualize=True``) is not provided; the name is here for programs that build
paths from it (they write there only if they choose to)."""

from sdar_tamp.compat.pddlstream.unsupported import not_provided

__all__ = ["VISUALIZATIONS_DIR"]

VISUALIZATIONS_DIR = "visualizations/"

__getattr__ = not_provided(__name__, "graph drawing (visualize=True) is not supported")
