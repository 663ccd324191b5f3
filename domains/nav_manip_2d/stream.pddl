; The streams of the 2-D house (bound in samplers.py): navigation poses per location, paths
; between configurations, placements per location and object, the pairwise collision test and
; the costs.
(define (stream nav-manip-2d)
  (:stream sample-navpose
    :inputs (?l) :domain (Location ?l)
    :outputs (?q) :certified (and (Conf ?q) (NavPose ?l ?q)))
  (:stream plan-path
    :inputs (?q1 ?q2) :domain (and (Conf ?q1) (Conf ?q2))
    :outputs (?t) :certified (and (Path ?t) (Motion ?q1 ?q2 ?t)))
  (:stream sample-place
    :inputs (?l ?o) :domain (and (Location ?l) (Obj ?o))
    :outputs (?p) :certified (and (Pose ?p) (Placeable ?l ?o ?p)))
  (:stream test-collision-free
    :inputs (?o1 ?p1 ?o2 ?p2) :domain (and (Obj ?o1) (Pose ?p1) (Obj ?o2) (Pose ?p2))
    :certified (CollisionFree ?o1 ?p1 ?o2 ?p2))
  (:function (PathLength ?t) (Path ?t))
  (:function (HandlingCost ?l ?o ?p ?q)
    (and (Location ?l) (Obj ?o) (Pose ?p) (Conf ?q))))
