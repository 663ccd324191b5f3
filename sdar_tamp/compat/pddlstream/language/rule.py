"""``pddlstream.language.rule``: rules (streams with no outputs applied eagerly).

Not provided here: PDDLStream's internal rule objects; :rule declarations are read by
sdar_tamp.language. The module exists so that PDDLStream's module tree is complete; any public
name of it raises :class:`~sdar_tamp.compat.pddlstream.unsupported.NotProvidedError` saying so."""

from sdar_tamp.compat.pddlstream.unsupported import not_provided

__all__: list[str] = []

__getattr__ = not_provided(
    __name__,
    "PDDLStream's internal rule objects; :rule declarations are read by sdar_tamp.language",
)
