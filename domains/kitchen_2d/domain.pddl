; A 2-D kitchen seen from above: cups (discs 0.3 m across) stand on rectangular regions (a
; counter, a shelf); a gripper moves between configurations along planned motions, picks a cup
; by a grasp and places it at a pose inside a region where it overlaps no other cup. Every
; geometric fact comes from a stream (stream.pddl); moves cost the distance travelled.
(define (domain kitchen-2d)
  (:requirements :strips :equality :negative-preconditions :derived-predicates
                 :existential-preconditions :action-costs)
  (:predicates
    (Cup ?c) (Region ?r) (Placeable ?c ?r)
    (Pose ?c ?p) (Grasp ?c ?g) (Conf ?q) (Traj ?t)
    (Contain ?c ?p ?r)                 ; cup ?c at pose ?p lies inside region ?r
    (Kin ?c ?p ?g ?q)                  ; the gripper at ?q holds ?c at ?p by ?g
    (Motion ?q1 ?t ?q2)                ; ?t takes the gripper from ?q1 to ?q2
    (CFree ?c ?p ?c2 ?p2)              ; ?c at ?p and ?c2 at ?p2 do not overlap
    (AtPose ?c ?p) (AtGrasp ?c ?g) (AtConf ?q) (HandEmpty) (CanMove)
    (In ?c ?r) (UnsafePose ?c ?p))
  (:functions (total-cost) (Distance ?q1 ?q2))

  (:derived (In ?c ?r)
    (exists (?p) (and (Contain ?c ?p ?r) (AtPose ?c ?p))))
  (:derived (UnsafePose ?c ?p)
    (exists (?c2 ?p2)
      (and (Pose ?c ?p) (AtPose ?c2 ?p2) (not (= ?c ?c2)) (not (CFree ?c ?p ?c2 ?p2)))))

  (:action move
    :parameters (?q1 ?t ?q2)
    :precondition (and (Motion ?q1 ?t ?q2) (Traj ?t) (AtConf ?q1) (CanMove))
    :effect (and (AtConf ?q2) (not (AtConf ?q1)) (not (CanMove))
                 (increase (total-cost) (Distance ?q1 ?q2))))
  (:action pick
    :parameters (?c ?p ?g ?q)
    :precondition (and (Kin ?c ?p ?g ?q) (AtPose ?c ?p) (HandEmpty) (AtConf ?q))
    :effect (and (AtGrasp ?c ?g) (CanMove) (not (AtPose ?c ?p)) (not (HandEmpty))
                 (increase (total-cost) 1)))
  (:action place
    :parameters (?c ?p ?g ?q)
    :precondition (and (Kin ?c ?p ?g ?q) (AtGrasp ?c ?g) (AtConf ?q) (not (UnsafePose ?c ?p)))
    :effect (and (AtPose ?c ?p) (HandEmpty) (CanMove) (not (AtGrasp ?c ?g))
                 (increase (total-cost) 1))))
