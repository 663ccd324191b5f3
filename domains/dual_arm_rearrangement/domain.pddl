; Minimal dual-arm rearrangement domain (placeholder for the stream file's parse test; the
; full domain is written with the task planner). Both arms move together between dual-arm
; configurations; an arm picks or places while the other waits or acts too.
(define (domain dual-arm-rearrangement)
  (:requirements :strips :equality :negative-preconditions)
  (:predicates
    (arm ?a) (obj ?o) (pose ?p) (buffer ?p) (objpose ?o ?p) (grasp ?o ?g)
    (conf ?a ?q) (kin ?a ?o ?p ?g ?q) (dualconf ?q) (combines ?q ?a1 ?q1 ?a2 ?q2)
    (traj ?t) (motion ?q1 ?t ?q2) (overlaps ?o ?p ?o2 ?p2) (cfree-conf-pose ?a ?q ?o ?p)
    (atpose ?o ?p) (holding ?a ?o ?g) (empty ?a) (atdualconf ?q) (atconf ?a ?q))
  (:action move
    :parameters (?q1 ?t ?q2)
    :precondition (and (atdualconf ?q1) (motion ?q1 ?t ?q2))
    :effect (and (atdualconf ?q2) (not (atdualconf ?q1))))
  (:action pick
    :parameters (?a ?o ?p ?g ?q ?dq ?a2 ?q2)
    :precondition (and (kin ?a ?o ?p ?g ?q) (combines ?dq ?a ?q ?a2 ?q2) (atdualconf ?dq)
                       (atpose ?o ?p) (empty ?a))
    :effect (and (holding ?a ?o ?g) (not (atpose ?o ?p)) (not (empty ?a))))
  (:action place
    :parameters (?a ?o ?p ?g ?q ?dq ?a2 ?q2)
    :precondition (and (kin ?a ?o ?p ?g ?q) (combines ?dq ?a ?q ?a2 ?q2) (atdualconf ?dq)
                       (holding ?a ?o ?g))
    :effect (and (atpose ?o ?p) (empty ?a) (not (holding ?a ?o ?g)))))
