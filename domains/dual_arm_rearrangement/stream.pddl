; Streams of synchronous multi-arm rearrangement (bound in streams/stream_map.py).
; Poses are planar object poses (x, y, yaw); arm configurations are per arm, combined into
; cell configurations (every arm; type dualconf) between which synchronous motions are
; planned. Type names used as unary facts type the outputs (grasp, armconf, pose, dualconf,
; traj).
(define (stream dual-arm-rearrangement)
  ; grasps of an object: top-down first, then growing tilt angles
  (:stream sample-grasp
    :inputs (?o) :domain (obj ?o)
    :outputs (?g) :certified (and (grasp ?g) (graspof ?o ?g)))
  ; collision-free IK branches (with pre-grasp) for an arm grasping ?o at ?p with ?g,
  ; among the objects resting in the state of the step (fluent atpose), best ranked first
  (:stream inverse-kinematics
    :inputs (?a ?o ?p ?g) :domain (and (arm ?a) (objpose ?o ?p) (graspof ?o ?g))
    :fluents (atpose)
    :outputs (?q) :certified (and (armconf ?q) (confof ?a ?q) (kin ?a ?o ?p ?g ?q)))
  ; free, reachable temporary poses for ?o (clear of resting objects and of goals)
  (:stream sample-buffer
    :inputs (?o) :domain (obj ?o)
    :fluents (atpose)
    :outputs (?p) :certified (and (pose ?p) (objpose ?o ?p) (buffer ?p)))
  ; a cell configuration from one configuration per arm (the arms clear of each other).
  ; Declared here for the two-arm cell; for a cell of k arms the problem declares it with k
  ; pairs, ?a1 ?q1 ... ?ak ?qk, each arm's facts as the first's (sdar_tamp/app/cell_streams.py)
  (:stream combine-confs
    :inputs (?a1 ?q1 ?a2 ?q2) :domain (and (confof ?a1 ?q1) (confof ?a2 ?q2))
    :outputs (?d) :certified (and (dualconf ?d) (confin ?d ?a1 ?q1) (confin ?d ?a2 ?q2)))
  ; a synchronous, validated dual-arm motion among the resting and held objects of the step
  ; (trajectory optimisation, then arm untangling, then one arm at a time)
  (:stream plan-dual-motion
    :inputs (?d1 ?d2) :domain (and (dualconf ?d1) (dualconf ?d2))
    :fluents (atpose holding)
    :outputs (?t) :certified (and (traj ?t) (motion ?d1 ?t ?d2)))
  ; the same motion by trajectory optimisation alone (no fallbacks): cheap to try and to
  ; fail, so SDAR-M asks it first for the best candidates before paying for the fallbacks
  (:stream plan-dual-motion-quick
    :inputs (?d1 ?d2) :domain (and (dualconf ?d1) (dualconf ?d2))
    :fluents (atpose holding)
    :outputs (?t) :certified (and (traj ?t) (motion ?d1 ?t ?d2)))
  ; footprint overlap of two object poses: the edges of the dependency graph
  (:stream test-overlap
    :inputs (?o ?p ?o2 ?p2) :domain (and (objpose ?o ?p) (objpose ?o2 ?p2))
    :certified (overlaps ?o ?p ?o2 ?p2))
  ; the footprints of two object poses are clear of each other (placements)
  (:stream test-cfree
    :inputs (?o ?p ?o2 ?p2) :domain (and (objpose ?o ?p) (objpose ?o2 ?p2))
    :certified (cfree ?o ?p ?o2 ?p2))
  ; ?o at ?p leaves no grasp of ?o2 at ?p2 (a gripper box of every grasp meets ?o): an edge
  ; of the dependency graph that footprints miss (a finger needs room beside an object)
  (:stream test-blocks-grasps
    :inputs (?o ?p ?o2 ?p2) :domain (and (objpose ?o ?p) (objpose ?o2 ?p2))
    :certified (blocksgrasps ?o ?p ?o2 ?p2))
  ; the gripper holding ?o at ?p with ?g is clear of ?o2 at ?p2 (two objects placed at once)
  (:stream test-grasp-cfree
    :inputs (?o ?p ?g ?o2 ?p2) :domain (and (objpose ?o ?p) (graspof ?o ?g) (objpose ?o2 ?p2))
    :certified (graspcfree ?o ?p ?g ?o2 ?p2))
  ; the execution time [s] of a motion
  (:function (Duration ?t) (traj ?t))
  ; an estimate [s] of the synchronous motion between two dual-arm configurations
  (:function (Distance ?d1 ?d2) (and (dualconf ?d1) (dualconf ?d2)))
  ; an estimate [s] of one arm's motion between two of its configurations
  (:function (ArmDistance ?q1 ?q2) (and (armconf ?q1) (armconf ?q2)))
  ; an estimate [s] of how much longer than the least the arm's next motion from ?q will take
  ; on average (its target not yet known)
  (:function (NextMotion ?q) (armconf ?q)))
