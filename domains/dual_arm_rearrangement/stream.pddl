; Streams of synchronous dual-arm rearrangement (bound in streams/stream_map.py).
; Poses are planar object poses (x, y, yaw); configurations are per arm, combined into
; dual-arm configurations between which synchronous motions are planned.
(define (stream dual-arm-rearrangement)
  ; grasps of an object: top-down first, then growing tilt angles
  (:stream sample-grasp
    :inputs (?o) :domain (obj ?o)
    :outputs (?g) :certified (grasp ?o ?g))
  ; collision-free IK branches (with pre-grasp) for an arm grasping ?o at ?p with ?g
  (:stream inverse-kinematics
    :inputs (?a ?o ?p ?g) :domain (and (arm ?a) (objpose ?o ?p) (grasp ?o ?g))
    :fluents (atpose)
    :outputs (?q) :certified (and (conf ?a ?q) (kin ?a ?o ?p ?g ?q)))
  ; free, reachable temporary poses for ?o
  (:stream sample-buffer
    :inputs (?o) :domain (obj ?o)
    :fluents (atpose)
    :outputs (?p) :certified (and (pose ?p) (objpose ?o ?p) (buffer ?p)))
  ; a dual-arm configuration from one configuration per arm
  (:stream combine-confs
    :inputs (?a1 ?q1 ?a2 ?q2) :domain (and (conf ?a1 ?q1) (conf ?a2 ?q2))
    :outputs (?q) :certified (and (dualconf ?q) (combines ?q ?a1 ?q1 ?a2 ?q2)))
  ; a synchronous, validated dual-arm motion (with its fallback level)
  (:stream plan-dual-motion
    :inputs (?q1 ?q2) :domain (and (dualconf ?q1) (dualconf ?q2))
    :fluents (atpose holding)
    :outputs (?t) :certified (and (traj ?t) (motion ?q1 ?t ?q2)))
  ; footprint overlap of two object poses: the edges of the dependency graph
  (:stream test-overlap
    :inputs (?o ?p ?o2 ?p2) :domain (and (objpose ?o ?p) (objpose ?o2 ?p2))
    :certified (overlaps ?o ?p ?o2 ?p2))
  ; an arm configuration clear of an object at a pose
  (:stream test-cfree-conf-pose
    :inputs (?a ?q ?o ?p) :domain (and (conf ?a ?q) (objpose ?o ?p))
    :certified (cfree-conf-pose ?a ?q ?o ?p)))
