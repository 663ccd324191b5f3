"""``pddlstream.retired.synthesizer``: stream synthesizers.

Not provided here: a retired PDDLStream module. The module exists so that PDDLStream's module
tree is complete; any public name of it raises
:class:`~sdar_tamp.compat.pddlstream.unsupported.NotProvidedError` saying so."""

from sdar_tamp.compat.pddlstream.unsupported import not_provided

__all__: list[str] = []

__getattr__ = not_provided(__name__, "a retired PDDLStream module")
