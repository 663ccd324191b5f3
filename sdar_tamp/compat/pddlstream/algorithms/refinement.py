"""``pddlstream.algorithms.refinement``: module flags a program may set.

``CONSTRAIN_PLANS`` added constraints against repeating failed plans in PDDLStream's focused
algorithm; the core algorithms keep their own bookkeeping, so the flag has no effect."""

from sdar_tamp.compat.pddlstream.unsupported import not_provided

__all__ = ["CONSTRAIN_PLANS"]

CONSTRAIN_PLANS = False

__getattr__ = not_provided(
    __name__,
    "PDDLStream's refinement internals; the focused algorithms here refine plans themselves",
)
