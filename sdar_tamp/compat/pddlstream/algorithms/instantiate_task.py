"""``pddlstream.algorithms.instantiate_task``: module flags a program may set.

``FD_INSTANTIATE`` selected Fast Downward's grounder in PDDLStream; grounding here is always the
core planner's, so the flag is accepted and has no effect."""

FD_INSTANTIATE = True
