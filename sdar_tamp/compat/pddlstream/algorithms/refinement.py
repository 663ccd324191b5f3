"""``pddlstream.algorithms.refinement``: module flags a program may set.

``CONSTRAIN_PLANS`` added constraints against repeating failed plans in PDDLStream's focused
algorithm; the core algorithms keep their own bookkeeping, so the flag has no effect."""

CONSTRAIN_PLANS = False
