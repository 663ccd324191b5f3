; Put a block into a region. In the shipped problem the goal region is narrower than the block,
; so no stable pose inside it exists: the problem is infeasible, and the pose sampler (finite)
; proves it by running dry.
(define (domain narrow-region)
  (:requirements :strips :typing :equality :negative-preconditions :derived-predicates
                 :existential-preconditions)
  (:types block region pose)
  (:predicates
    (blockpose ?b - block ?p - pose) (contained ?b - block ?p - pose ?r - region)
    (cfree ?b - block ?p - pose ?b2 - block ?p2 - pose)
    (atpose ?b - block ?p - pose) (holding ?b - block) (handempty)
    (in ?b - block ?r - region) (unsafe ?b - block ?p - pose))
  (:derived (in ?b - block ?r - region)
    (exists (?p - pose) (and (contained ?b ?p ?r) (atpose ?b ?p))))
  (:derived (unsafe ?b - block ?p - pose)
    (exists (?b2 - block ?p2 - pose)
      (and (atpose ?b2 ?p2) (not (= ?b ?b2)) (not (cfree ?b ?p ?b2 ?p2)))))
  (:action pick
    :parameters (?b - block ?p - pose)
    :precondition (and (atpose ?b ?p) (handempty))
    :effect (and (holding ?b) (not (atpose ?b ?p)) (not (handempty))))
  (:action place
    :parameters (?b - block ?p - pose)
    :precondition (and (holding ?b) (blockpose ?b ?p) (not (unsafe ?b ?p)))
    :effect (and (atpose ?b ?p) (handempty) (not (holding ?b)))))
