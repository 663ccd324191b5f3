"""``pddlstream.algorithms``: the solvers under PDDLStream's module names."""
