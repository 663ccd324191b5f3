; Samplers and tests of the 2-D pick-and-place world (bound in samplers.py).
; Type names used as unary facts type the outputs (pose, grasp, conf, traj).
(define (stream pick-place-2d)
  (:stream sample-pose
    :inputs (?b ?r) :domain (and (block ?b) (region ?r))
    :outputs (?p) :certified (and (pose ?p) (blockpose ?b ?p) (contained ?b ?p ?r)))
  (:stream sample-grasp
    :inputs (?b) :domain (block ?b)
    :outputs (?g) :certified (and (grasp ?g) (blockgrasp ?b ?g)))
  (:stream inverse-kinematics
    :inputs (?b ?p ?g) :domain (and (blockpose ?b ?p) (blockgrasp ?b ?g))
    :outputs (?q) :certified (and (conf ?q) (kin ?b ?p ?g ?q)))
  (:stream plan-free-motion
    :inputs (?q1 ?q2) :domain (and (conf ?q1) (conf ?q2))
    :outputs (?t) :certified (and (traj ?t) (freemotion ?q1 ?t ?q2)))
  (:stream plan-holding-motion
    :inputs (?q1 ?q2 ?b ?g) :domain (and (conf ?q1) (conf ?q2) (blockgrasp ?b ?g))
    :outputs (?t) :certified (and (traj ?t) (holdingmotion ?q1 ?t ?q2 ?b ?g)))
  (:stream test-cfree-pose
    :inputs (?b ?p ?b2 ?p2) :domain (and (blockpose ?b ?p) (blockpose ?b2 ?p2))
    :certified (cfree ?b ?p ?b2 ?p2))
  ; an external predicate: evaluated on real trajectories, optimistically false on placeholders
  ; (the domain uses it under a negation, through the derived unsafetraj)
  (:predicate (TrajCollision ?t ?b2 ?p2) (and (traj ?t) (blockpose ?b2 ?p2))))
