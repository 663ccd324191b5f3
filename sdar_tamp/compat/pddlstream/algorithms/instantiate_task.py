"""``pddlstream.algorithms.instantiate_task``: Fast Downward's grounding of a task.

``FD_INSTANTIATE`` selected Fast Downward's grounder in PDDLStream; grounding here is always the
core planner's, so the flag is accepted and has no effect. ``instantiate_task`` and
``sas_from_pddl`` work on Fast Downward's task objects, which do not exist here: importing them
works, calling them raises :class:`~sdar_tamp.compat.pddlstream.unsupported.NotProvidedError`.
"""

from sdar_tamp.compat.pddlstream.unsupported import not_provided, unsupported_function

__all__ = ["FD_INSTANTIATE", "instantiate_task", "sas_from_pddl"]

_WHY = "it grounds Fast Downward task objects; grounding here is solvers.classical's"

FD_INSTANTIATE = True
instantiate_task = unsupported_function(__name__, "instantiate_task", _WHY)
sas_from_pddl = unsupported_function(__name__, "sas_from_pddl", _WHY)

__getattr__ = not_provided(__name__, _WHY)
