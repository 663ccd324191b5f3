"""``pddlstream.language.fluent``: fluent streams.

Not provided here: fluent streams are compiled as exogenous streams (see the exogenous semantics
in docs/pddlstream.md); PDDLStream's internal helpers are not provided. The module exists so
that PDDLStream's module tree is complete; any public name of it raises
:class:`~sdar_tamp.compat.pddlstream.unsupported.NotProvidedError` saying so."""

from sdar_tamp.compat.pddlstream.unsupported import not_provided

__all__: list[str] = []

__getattr__ = not_provided(
    __name__,
    (
        "fluent streams are compiled as exogenous streams (see the exogenous semantics in "
        "docs/pddlstream.md); PDDLStream's internal helpers are not provided"
    ),
)
