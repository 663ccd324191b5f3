"""``pddlstream.language.statistics``: stream statistics and their files.

Not provided here: learned statistics files are not supported; per-stream counts are in
Solution.statistics. The module exists so that PDDLStream's module tree is complete; any public
name of it raises :class:`~sdar_tamp.compat.pddlstream.unsupported.NotProvidedError` saying so."""

from sdar_tamp.compat.pddlstream.unsupported import not_provided

__all__: list[str] = []

__getattr__ = not_provided(
    __name__,
    "learned statistics files are not supported; per-stream counts are in Solution.statistics",
)
