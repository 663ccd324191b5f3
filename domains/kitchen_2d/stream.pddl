; The samplers, kinematics, motions, the collision test and the cost of the 2-D kitchen
; (bound in samplers.py).
(define (stream kitchen-2d)
  (:stream sample-pose
    :inputs (?c ?r) :domain (Placeable ?c ?r)
    :outputs (?p) :certified (and (Pose ?c ?p) (Contain ?c ?p ?r)))
  (:stream sample-grasp
    :inputs (?c) :domain (Cup ?c)
    :outputs (?g) :certified (Grasp ?c ?g))
  (:stream inverse-kinematics
    :inputs (?c ?p ?g) :domain (and (Pose ?c ?p) (Grasp ?c ?g))
    :outputs (?q) :certified (and (Conf ?q) (Kin ?c ?p ?g ?q)))
  (:stream plan-motion
    :inputs (?q1 ?q2) :domain (and (Conf ?q1) (Conf ?q2))
    :outputs (?t) :certified (and (Traj ?t) (Motion ?q1 ?t ?q2)))
  (:stream test-cfree
    :inputs (?c ?p ?c2 ?p2) :domain (and (Pose ?c ?p) (Pose ?c2 ?p2))
    :certified (CFree ?c ?p ?c2 ?p2))
  (:function (Distance ?q1 ?q2) (and (Conf ?q1) (Conf ?q2))))
