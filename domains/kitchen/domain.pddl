; A kitchen: carry food from the shelf to a sink, then to the stove, then serve it at the table.
; Moving the robot costs the distance travelled, computed by the (Distance ?q1 ?q2) function
; stream; every manipulation costs 1. Of two sinks, the one near the stove gives cheaper plans.
(define (domain kitchen)
  (:requirements :strips :typing :equality :action-costs)
  (:types item station conf)
  (:predicates
    (reaches ?q - conf ?s - station)   ; from ?q the robot can work at ?s
    (sink ?s - station) (stove ?s - station) (servingtable ?s - station)
    (on ?i - item ?s - station) (holding ?i - item) (handempty) (atconf ?q - conf)
    (cleaned ?i - item) (cooked ?i - item) (served ?i - item))
  (:functions (total-cost) (distance ?q1 - conf ?q2 - conf))

  (:action move
    :parameters (?q1 - conf ?q2 - conf)
    :precondition (and (atconf ?q1) (not (= ?q1 ?q2)))
    :effect (and (atconf ?q2) (not (atconf ?q1)) (increase (total-cost) (distance ?q1 ?q2))))
  (:action pick
    :parameters (?i - item ?s - station ?q - conf)
    :precondition (and (on ?i ?s) (atconf ?q) (reaches ?q ?s) (handempty))
    :effect (and (holding ?i) (not (on ?i ?s)) (not (handempty)) (increase (total-cost) 1)))
  (:action place
    :parameters (?i - item ?s - station ?q - conf)
    :precondition (and (holding ?i) (atconf ?q) (reaches ?q ?s))
    :effect (and (on ?i ?s) (handempty) (not (holding ?i)) (increase (total-cost) 1)))
  (:action clean
    :parameters (?i - item ?s - station ?q - conf)
    :precondition (and (on ?i ?s) (sink ?s) (atconf ?q) (reaches ?q ?s))
    :effect (and (cleaned ?i) (increase (total-cost) 1)))
  (:action cook
    :parameters (?i - item ?s - station ?q - conf)
    :precondition (and (on ?i ?s) (stove ?s) (cleaned ?i) (atconf ?q) (reaches ?q ?s))
    :effect (and (cooked ?i) (increase (total-cost) 1)))
  (:action serve
    :parameters (?i - item ?s - station ?q - conf)
    :precondition (and (on ?i ?s) (servingtable ?s) (cooked ?i) (atconf ?q) (reaches ?q ?s))
    :effect (and (served ?i) (increase (total-cost) 1))))
