; Two arms swap two objects: each object's goal is the other one's start. The left arm reaches
; only the left part of the table and the right arm only the right part, so an object crosses
; over by a hand-over or through a buffer pose in the shared middle; and since neither goal is
; free before the other object leaves it, one object has to wait somewhere first.
(define (domain dual-arm-swap)
  (:requirements :strips :typing :equality :negative-preconditions :derived-predicates
                 :existential-preconditions :action-costs)
  (:types arm obj pose)
  (:predicates
    (objpose ?o - obj ?p - pose)                    ; ?o may stand at ?p
    (buffer ?p - pose)                              ; ?p was sampled as a buffer
    (reachable ?a - arm ?p - pose)
    (cfree ?o - obj ?p - pose ?o2 - obj ?p2 - pose)
    (atpose ?o - obj ?p - pose) (holding ?a - arm ?o - obj) (empty ?a - arm)
    (unsafe ?o - obj ?p - pose))
  (:functions (total-cost))
  (:derived (unsafe ?o - obj ?p - pose)
    (exists (?o2 - obj ?p2 - pose)
      (and (atpose ?o2 ?p2) (not (= ?o ?o2)) (not (cfree ?o ?p ?o2 ?p2)))))
  (:action pick
    :parameters (?a - arm ?o - obj ?p - pose)
    :precondition (and (atpose ?o ?p) (reachable ?a ?p) (empty ?a))
    :effect (and (holding ?a ?o) (not (atpose ?o ?p)) (not (empty ?a)) (increase (total-cost) 1)))
  (:action place
    :parameters (?a - arm ?o - obj ?p - pose)
    :precondition (and (holding ?a ?o) (objpose ?o ?p) (reachable ?a ?p) (not (unsafe ?o ?p)))
    :effect (and (atpose ?o ?p) (empty ?a) (not (holding ?a ?o)) (increase (total-cost) 1)))
  (:action handover
    :parameters (?from - arm ?to - arm ?o - obj)
    :precondition (and (holding ?from ?o) (empty ?to) (not (= ?from ?to)))
    :effect (and (holding ?to ?o) (empty ?from) (not (holding ?from ?o)) (not (empty ?to))
                 (increase (total-cost) 2))))
