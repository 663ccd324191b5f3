"""``pddlstream.algorithms``: the solvers under PDDLStream's module names."""

__all__: list[str] = []
