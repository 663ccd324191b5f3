"""``pddlstream.algorithms.scheduling.postprocess``: stream-plan scheduling: postprocess.

Not provided here: PDDLStream's stream-plan scheduling internals (it recovers stream plans from
Fast Downward's output); the solvers here schedule streams themselves (solvers.stream_planning).
The module exists so that PDDLStream's module tree is complete; any public name of it raises
:class:`~sdar_tamp.compat.pddlstream.unsupported.NotProvidedError` saying so."""

from sdar_tamp.compat.pddlstream.unsupported import SCHEDULING_INTERNALS, not_provided

__all__: list[str] = []

__getattr__ = not_provided(__name__, SCHEDULING_INTERNALS)
