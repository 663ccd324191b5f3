"""``pddlstream.algorithms.reorder``: stream-plan reordering by learned statistics.

Not provided here: stream plans are ordered by the solver here; learned statistics files are not
supported. The module exists so that PDDLStream's module tree is complete; any public name of it
raises :class:`~sdar_tamp.compat.pddlstream.unsupported.NotProvidedError` saying so."""

from sdar_tamp.compat.pddlstream.unsupported import not_provided

__all__: list[str] = []

__getattr__ = not_provided(
    __name__,
    "stream plans are ordered by the solver here; learned statistics files are not supported",
)
