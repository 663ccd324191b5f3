"""sdar-tamp: declarative task-and-motion planning with PDDL streams.

Kept light on purpose: importing the package loads no geometry or solver code.
"""

from sdar_tamp.errors import SdarError

__version__ = "0.1.0"

__all__ = ["SdarError", "__version__"]
