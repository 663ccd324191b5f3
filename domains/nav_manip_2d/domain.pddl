; A 2-D house seen from above: a mobile robot drives between locations (a counter, a table, a
; shelf) along planned paths, and moves objects (discs) between them. Navigation poses and
; placements come from streams; a placement must not overlap any object already at the
; location (a collision test used through a derived predicate, as PDDLStream programs do);
; driving costs the path's length, picking and placing a cost that depends on where the
; robot stands, the object and its pose.
(define (domain nav-manip-2d)
  (:requirements :strips :equality :negative-preconditions :derived-predicates
                 :existential-preconditions :action-costs)
  (:predicates
    (Robot ?r) (Obj ?o) (Location ?l) (Pose ?p) (Conf ?q) (Path ?t)
    (NavPose ?l ?q)                    ; from ?q the robot reaches location ?l
    (Motion ?q1 ?q2 ?t)                ; ?t drives the robot from ?q1 to ?q2
    (Placeable ?l ?o ?p)               ; ?o at ?p lies on location ?l
    (CollisionFree ?o1 ?p1 ?o2 ?p2)    ; ?o1 at ?p1 and ?o2 at ?p2 do not overlap
    (At ?e ?l) (AtConf ?r ?q) (AtPose ?o ?p) (Holding ?r ?o) (HandEmpty ?r)
    (Unsafe ?o ?p ?l))
  (:functions (total-cost) (PathLength ?t) (HandlingCost ?l ?o ?p ?q))

  (:derived (Unsafe ?o ?p ?l)
    (exists (?o2 ?p2)
      (and (Obj ?o) (Pose ?p) (Obj ?o2) (Pose ?p2) (At ?o2 ?l) (AtPose ?o2 ?p2) (not (= ?o ?o2))
           (not (CollisionFree ?o ?p ?o2 ?p2)))))

  (:action navigate
    :parameters (?r ?l1 ?l2 ?q1 ?q2 ?t)
    :precondition (and (Robot ?r) (At ?r ?l1) (not (= ?l1 ?l2)) (AtConf ?r ?q1)
                       (NavPose ?l2 ?q2) (Motion ?q1 ?q2 ?t))
    :effect (and (At ?r ?l2) (not (At ?r ?l1)) (AtConf ?r ?q2) (not (AtConf ?r ?q1))
                 (increase (total-cost) (PathLength ?t))))
  (:action pick
    :parameters (?r ?o ?l ?p ?q)
    :precondition (and (Robot ?r) (Obj ?o) (At ?r ?l) (AtConf ?r ?q) (NavPose ?l ?q)
                       (At ?o ?l) (AtPose ?o ?p) (HandEmpty ?r))
    :effect (and (Holding ?r ?o) (not (HandEmpty ?r)) (not (At ?o ?l)) (not (AtPose ?o ?p))
                 (increase (total-cost) (HandlingCost ?l ?o ?p ?q))))
  (:action place
    :parameters (?r ?o ?l ?p ?q)
    :precondition (and (Robot ?r) (At ?r ?l) (AtConf ?r ?q) (NavPose ?l ?q) (Holding ?r ?o)
                       (Placeable ?l ?o ?p) (not (Unsafe ?o ?p ?l)))
    :effect (and (HandEmpty ?r) (At ?o ?l) (AtPose ?o ?p) (not (Holding ?r ?o))
                 (increase (total-cost) (HandlingCost ?l ?o ?p ?q)))))
