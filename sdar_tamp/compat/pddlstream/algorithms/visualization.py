"""``pddlstream.algorithms.visualization``: where PDDLStream writes its pictures.

Graph drawing (``visualize=True``) is not provided; the name is here for programs that build
paths from it (they write there only if they choose to)."""

VISUALIZATIONS_DIR = "visualizations/"
