"""Pictures of plans: an interactive 3-D replay (HTML, plotly) and top-down storyboards
(PNG panels or a GIF animation, matplotlib).

Both viewers take an :class:`~sdar_tamp.world.instance.Instance` and a plan with the attributes
of :class:`sdar_tamp.plan_file.PlanFile` (see :class:`PlanLike`); plotly and matplotlib are the
optional ``viz`` extra and are imported only when a picture is written.
"""

from sdar_tamp.viewer._plan import ArmLike, EventLike, PlanLike, StepLike
from sdar_tamp.viewer.errors import MissingDependencyError
from sdar_tamp.viewer.html import write_html
from sdar_tamp.viewer.pictures import show
from sdar_tamp.viewer.storyboard import write_storyboard

__all__ = [
    "ArmLike",
    "EventLike",
    "MissingDependencyError",
    "PlanLike",
    "StepLike",
    "show",
    "write_html",
    "write_storyboard",
]
