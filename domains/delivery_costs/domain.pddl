; Delivery with action costs: driving costs the road's length (a function term), loading and
; unloading a fixed amount (a number). Plans are compared by (total-cost), not by length.
(define (domain delivery-costs)
  (:requirements :strips :typing :action-costs)
  (:types place vehicle package)
  (:predicates (road ?a ?b - place) (at ?v - vehicle ?p - place)
               (parcel-at ?x - package ?p - place) (carries ?v - vehicle ?x - package))
  (:functions (total-cost) - number (length ?a ?b - place) - number)

  (:action drive
    :parameters (?v - vehicle ?from ?to - place)
    :precondition (and (at ?v ?from) (road ?from ?to))
    :effect (and (at ?v ?to) (not (at ?v ?from)) (increase (total-cost) (length ?from ?to))))

  (:action load
    :parameters (?v - vehicle ?x - package ?p - place)
    :precondition (and (at ?v ?p) (parcel-at ?x ?p))
    :effect (and (carries ?v ?x) (not (parcel-at ?x ?p)) (increase (total-cost) 1)))

  (:action unload
    :parameters (?v - vehicle ?x - package ?p - place)
    :precondition (and (at ?v ?p) (carries ?v ?x))
    :effect (and (parcel-at ?x ?p) (not (carries ?v ?x)) (increase (total-cost) 1))))
