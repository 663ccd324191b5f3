"""``pddlstream.algorithms.disabled``: disabled stream instances.

Not provided here: PDDLStream's skeleton queue and stream-plan internals; the adaptive algorithm
here keeps its own (solvers.stream_planning). The module exists so that PDDLStream's module tree
is complete; any public name of it raises
:class:`~sdar_tamp.compat.pddlstream.unsupported.NotProvidedError` saying so."""

from sdar_tamp.compat.pddlstream.unsupported import SKELETON_INTERNALS, not_provided

__all__: list[str] = []

__getattr__ = not_provided(__name__, SKELETON_INTERNALS)
