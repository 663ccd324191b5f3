"""``pddlstream.algorithms.instantiation``: module flags a program may set.

``USE_RELATION`` chose PDDLStream's relational stream instantiation; the core instantiator
(:mod:`solvers.stream_planning.facts`) always joins relations, so the flag has no effect."""

from sdar_tamp.compat.pddlstream.unsupported import not_provided

__all__ = ["USE_RELATION"]

USE_RELATION = False

__getattr__ = not_provided(
    __name__,
    (
        "PDDLStream's instantiation internals (its Instantiator); stream instances are "
        "managed by the solvers here"
    ),
)
