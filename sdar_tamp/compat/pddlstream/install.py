"""Importing this module makes ``import pddlstream...`` resolve to the compatibility tree::

    import sdar_tamp.compat.pddlstream.install  # noqa: F401  (first line of the program)

See :mod:`sdar_tamp.compat.pddlstream.alias`.
"""

from sdar_tamp.compat.pddlstream.alias import install_alias

install_alias()
