"""``pddlstream.algorithms.instantiation``: module flags a program may set.

``USE_RELATION`` chose PDDLStream's relational stream instantiation; the core instantiator
(:mod:`solvers.stream_planning.facts`) always joins relations, so the flag has no effect."""

USE_RELATION = False
