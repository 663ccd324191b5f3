"""The names through which SDAR reads a rearrangement domain and its stream file.

SDAR is not tied to one domain: any rearrangement domain whose stream file declares streams
with these roles (and whose domain has these predicates and actions) can be solved by it. The
defaults are the names of ``domains/dual_arm_rearrangement``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields

from sdar_tamp.errors import ParameterError
from sdar_tamp.language.domain_model import Domain
from solvers.stream_planning.externals import FunctionExternal, StreamExternal


@dataclass(frozen=True)
class SdarVocabulary:
    """Stream, function, predicate, type and action names by role."""

    # streams
    overlap: str = "test-overlap"  # (?o ?p ?o2 ?p2): o at p overlaps o2 at p2
    cfree: str = "test-cfree"  # (?o ?p ?o2 ?p2): certifies the placement precondition
    grasp: str = "sample-grasp"  # (?o) -> ?g
    ik: str = "inverse-kinematics"  # (?arm ?o ?p ?g) -> ?q, fluent atpose
    buffer: str = "sample-buffer"  # (?o) -> ?p, fluent atpose
    combine: str = "combine-confs"  # (?a1 ?q1 ... ?ak ?qk) -> ?d: one pair per arm, in
    # arm-name order (the problem declares it for its cell's k arms)
    motion: str = "plan-dual-motion"  # (?d1 ?d2) -> ?t, fluents atpose holding
    quick_motion: str = "plan-dual-motion-quick"  # the same, cheaper and weaker (optional)
    distance: str = "distance"  # function (?d1 ?d2): estimated motion time (optional)
    arm_distance: str = "armdistance"  # function (?q1 ?q2): one arm's estimated motion time
    # (optional: a placement's configuration is then the one reached soonest from the pick)
    next_motion: str = "nextmotion"  # function (?q): expected extra time of the arm's next
    # motion from ?q (optional: added to arm_distance when choosing a placement)
    blocks_grasps: str = "test-blocks-grasps"  # (?o ?p ?o2 ?p2): o at p leaves o2 no grasp
    # at p2 (optional: dependency edges beyond footprint overlap)
    grasp_cfree: str = "test-grasp-cfree"  # (?o ?p ?g ?o2 ?p2): the gripper holding o at p
    # with g is clear of o2 at p2 (optional: two objects placed at once)
    # predicates and types
    atpose: str = "atpose"
    holding: str = "holding"
    atdualconf: str = "atdualconf"
    confin: str = "confin"
    buffer_pose: str = "buffer"
    unsafe: str = "unsafe"
    arm_type: str = "arm"
    # actions
    move: str = "move"
    pick: str = "pick"
    place: str = "place"
    pick_both: str = "pick-both"  # two grippers at once; three or more: consecutive picks
    place_both: str = "place-both"

    def check(
        self,
        domain: Domain,
        streams: Mapping[str, StreamExternal],
        functions: Mapping[str, FunctionExternal],
    ) -> None:
        """Raise :class:`ParameterError` naming every role the problem does not provide."""
        missing: list[str] = []
        for role in ("overlap", "cfree", "grasp", "ik", "buffer", "combine", "motion"):
            name = getattr(self, role)
            if name not in streams:
                missing.append(f"stream {name!r} ({role})")
        predicates = set(domain.predicates) | domain.derived_predicates
        for role in ("atpose", "holding", "atdualconf", "confin", "buffer_pose", "unsafe"):
            name = getattr(self, role)
            if name not in predicates:
                missing.append(f"predicate {name!r} ({role})")
        actions = {a.name for a in domain.actions}
        for role in ("move", "pick", "place", "pick_both", "place_both"):
            name = getattr(self, role)
            if name not in actions:
                missing.append(f"action {name!r} ({role})")
        if self.arm_type not in domain.types.parents:
            missing.append(f"type {self.arm_type!r} (arm_type)")
        if missing:
            raise ParameterError(
                "algorithm 'sdar' needs a rearrangement domain; missing: " + "; ".join(missing)
            )


ROLES = tuple(f.name for f in fields(SdarVocabulary))
