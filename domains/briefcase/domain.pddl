; Briefcase with lights: carry documents in a briefcase through a house.
; - moving the case moves everything inside it (universal conditional effect);
; - a room can only be entered when it is visible: its light is on, or a lamp is in the case
;   (derived predicates, a disjunction and an existential);
; - the case holds at most two items (a derived predicate with negated equality, used negated);
; - a switch toggles the light of a room (conditional effects on a negative condition);
; - the goal asks for every document in the office and all lights off (universal goal over a
;   derived predicate defined by negation).
(define (domain briefcase)
  (:requirements :strips :typing :negative-preconditions :disjunctive-preconditions :equality
                 :existential-preconditions :universal-preconditions :conditional-effects
                 :derived-predicates)
  (:types room item - object
          document lamp - item)
  (:predicates
    (case-at ?r - room)
    (at ?i - item ?r - room)
    (in ?i - item)
    (door ?a ?b - room)
    (light-on ?r - room)
    (switch ?s ?r - room)
    (has-lamp)
    (visible ?r - room)
    (full)
    (dark ?r - room))

  (:derived (has-lamp) (exists (?l - lamp) (in ?l)))
  (:derived (visible ?r - room) (or (light-on ?r) (has-lamp)))
  (:derived (full)
    (exists (?a ?b - item) (and (in ?a) (in ?b) (not (= ?a ?b)))))
  (:derived (dark ?r - room) (not (light-on ?r)))

  (:action move
    :parameters (?from ?to - room)
    :precondition (and (case-at ?from) (not (= ?from ?to))
                       (or (door ?from ?to) (door ?to ?from))
                       (visible ?to))
    :effect (and (case-at ?to) (not (case-at ?from))
                 (forall (?i - item)
                   (when (in ?i) (and (at ?i ?to) (not (at ?i ?from)))))))

  (:action put-in
    :parameters (?i - item ?r - room)
    :precondition (and (case-at ?r) (at ?i ?r) (not (in ?i)) (not (full)))
    :effect (in ?i))

  (:action take-out
    :parameters (?i - item ?r - room)
    :precondition (and (case-at ?r) (in ?i))
    :effect (not (in ?i)))

  (:action toggle
    :parameters (?s ?r - room)
    :precondition (and (case-at ?s) (switch ?s ?r))
    :effect (and (when (light-on ?r) (not (light-on ?r)))
                 (when (not (light-on ?r)) (light-on ?r)))))
