"""``pddlstream.algorithms.serialized``: serialized (goal-by-goal) solving.

Not provided here: solve_serialized and its helpers are not provided; solve() plans for the
whole goal. The module exists so that PDDLStream's module tree is complete; any public name of
it raises :class:`~sdar_tamp.compat.pddlstream.unsupported.NotProvidedError` saying so."""

from sdar_tamp.compat.pddlstream.unsupported import not_provided

__all__: list[str] = []

__getattr__ = not_provided(
    __name__, "solve_serialized and its helpers are not provided; solve() plans for the whole goal"
)
