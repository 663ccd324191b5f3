"""``pddlstream.algorithms.algorithm``: the shared set-up of PDDLStream's algorithms.

Not provided here: PDDLStream's internal problem set-up (parse_problem over its own language
objects); use solve() or PDDLProblem. The module exists so that PDDLStream's module tree is
complete; any public name of it raises
:class:`~sdar_tamp.compat.pddlstream.unsupported.NotProvidedError` saying so."""

from sdar_tamp.compat.pddlstream.unsupported import not_provided

__all__: list[str] = []

__getattr__ = not_provided(
    __name__,
    (
        "PDDLStream's internal problem set-up (parse_problem over its own language objects); "
        "use solve() or PDDLProblem"
    ),
)
