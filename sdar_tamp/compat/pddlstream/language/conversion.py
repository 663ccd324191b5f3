"""``pddlstream.language.conversion``: conversion between PDDLStream's expressions and Fast
Downward's.

Not provided here: PDDLStream's internal expression conversion; facts here are plain tuples read
by sdar_tamp.language. The module exists so that PDDLStream's module tree is complete; any
public name of it raises :class:`~sdar_tamp.compat.pddlstream.unsupported.NotProvidedError`
saying so."""

from sdar_tamp.compat.pddlstream.unsupported import not_provided

__all__: list[str] = []

__getattr__ = not_provided(
    __name__,
    (
        "PDDLStream's internal expression conversion; facts here are plain tuples read by "
        "sdar_tamp.language"
    ),
)
