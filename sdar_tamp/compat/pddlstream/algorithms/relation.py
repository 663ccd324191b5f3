"""``pddlstream.algorithms.relation``: relational grounding.

Not provided here: Fast Downward's translator and search internals; planning here is the core
classical planner (solvers.classical). The module exists so that PDDLStream's module tree is
complete; any public name of it raises
:class:`~sdar_tamp.compat.pddlstream.unsupported.NotProvidedError` saying so."""

from sdar_tamp.compat.pddlstream.unsupported import FAST_DOWNWARD_INTERNALS, not_provided

__all__: list[str] = []

__getattr__ = not_provided(__name__, FAST_DOWNWARD_INTERNALS)
