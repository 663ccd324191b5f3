; Synchronous multi-arm tabletop rearrangement (k arms; the shipped paper cell has two).
;
; The arms always move together: a (move ?d1 ?t ?d2) takes every arm from one cell
; configuration to another along one synchronous trajectory (an arm that has nothing to do
; waits in place). A cell configuration (type dualconf, named for the two-arm cell it began
; with) holds one (confin ?d ?a ?q) fact per arm, so nothing here counts the arms. Between
; motions the grippers act: one arm alone (pick / place, while the other arms hold objects or
; wait), two at the same instant (pick-both / place-both, e.g. the two halves of a dual-arm
; swap), or three or more at the same instant, written as consecutive pick / place actions at
; one configuration with no move between them (e.g. an m-cycle rotated by m arms: every object
; lifted, then every object placed). A PDDL action has a fixed arity, so a gripper action for
; every number of arms would need one action per count; consecutive actions need none, each
; placement's precondition then sees the objects placed before it at that instant (their
; clearance is certified pairwise), and the plan's timeline makes them one instant with one
; dwell. Objects go to their goals or to buffers (free temporary poses) with the same actions.
;
; A placement needs a free pose: (unsafe ?o ?p) holds when some other resting object is not
; certified collision-free with ?o at ?p (closed world: an untested pair counts as unsafe).
;
; Costs are execution time [s]: a motion costs its duration, a gripper action the problem's
; (gripper-time), whether one gripper or both act; consecutive pick / place actions at one
; instant each count one (gripper-time), so for three or more grippers at once the total cost
; exceeds the plan's execution time, which counts one dwell per instant. (distance ?d1 ?d2)
; estimates a motion's duration before it is planned (used to rank candidates).
(define (domain dual-arm-rearrangement)
  (:requirements :strips :typing :equality :negative-preconditions :existential-preconditions
                 :derived-predicates :action-costs)
  (:types arm obj pose grasp armconf dualconf traj)
  (:predicates
    ; static facts, certified by the streams of stream.pddl
    (objpose ?o - obj ?p - pose)                      ; ?p is a pose of ?o
    (buffer ?p - pose)                                ; ?p is a temporary pose
    (graspof ?o - obj ?g - grasp)
    (confof ?a - arm ?q - armconf)
    (kin ?a - arm ?o - obj ?p - pose ?g - grasp ?q - armconf)
    (confin ?d - dualconf ?a - arm ?q - armconf)      ; in ?d, arm ?a is at ?q
    (motion ?d1 - dualconf ?t - traj ?d2 - dualconf)
    (overlaps ?o - obj ?p - pose ?o2 - obj ?p2 - pose)
    (cfree ?o - obj ?p - pose ?o2 - obj ?p2 - pose)
    (blocksgrasps ?o - obj ?p - pose ?o2 - obj ?p2 - pose)  ; ?o at ?p leaves ?o2 no grasp
    (graspcfree ?o - obj ?p - pose ?g - grasp ?o2 - obj ?p2 - pose)
    ; fluents
    (atpose ?o - obj ?p - pose)
    (holding ?a - arm ?o - obj ?g - grasp)
    (empty ?a - arm)
    (atdualconf ?d - dualconf)
    ; derived
    (unsafe ?o - obj ?p - pose))
  (:functions (total-cost) (duration ?t - traj) (distance ?d1 - dualconf ?d2 - dualconf)
              (gripper-time))

  (:derived (unsafe ?o - obj ?p - pose)
    (exists (?o2 - obj ?p2 - pose)
      (and (objpose ?o ?p) (atpose ?o2 ?p2) (not (= ?o ?o2)) (not (cfree ?o ?p ?o2 ?p2)))))

  (:action move
    :parameters (?d1 - dualconf ?t - traj ?d2 - dualconf)
    :precondition (and (atdualconf ?d1) (motion ?d1 ?t ?d2))
    :effect (and (atdualconf ?d2) (not (atdualconf ?d1))
                 (increase (total-cost) (duration ?t))))

  (:action pick
    :parameters (?a - arm ?o - obj ?p - pose ?g - grasp ?q - armconf ?d - dualconf)
    :precondition (and (atdualconf ?d) (confin ?d ?a ?q) (kin ?a ?o ?p ?g ?q)
                       (atpose ?o ?p) (empty ?a))
    :effect (and (holding ?a ?o ?g) (not (atpose ?o ?p)) (not (empty ?a))
                 (increase (total-cost) (gripper-time))))

  (:action place
    :parameters (?a - arm ?o - obj ?p - pose ?g - grasp ?q - armconf ?d - dualconf)
    :precondition (and (atdualconf ?d) (confin ?d ?a ?q) (kin ?a ?o ?p ?g ?q)
                       (holding ?a ?o ?g) (not (unsafe ?o ?p)))
    :effect (and (atpose ?o ?p) (empty ?a) (not (holding ?a ?o ?g))
                 (increase (total-cost) (gripper-time))))

  (:action pick-both
    :parameters (?d - dualconf
                 ?a1 - arm ?o1 - obj ?p1 - pose ?g1 - grasp ?q1 - armconf
                 ?a2 - arm ?o2 - obj ?p2 - pose ?g2 - grasp ?q2 - armconf)
    :precondition (and (not (= ?a1 ?a2)) (not (= ?o1 ?o2)) (atdualconf ?d)
                       (confin ?d ?a1 ?q1) (kin ?a1 ?o1 ?p1 ?g1 ?q1) (atpose ?o1 ?p1) (empty ?a1)
                       (confin ?d ?a2 ?q2) (kin ?a2 ?o2 ?p2 ?g2 ?q2) (atpose ?o2 ?p2) (empty ?a2))
    :effect (and (holding ?a1 ?o1 ?g1) (not (atpose ?o1 ?p1)) (not (empty ?a1))
                 (holding ?a2 ?o2 ?g2) (not (atpose ?o2 ?p2)) (not (empty ?a2))
                 (increase (total-cost) (gripper-time))))

  (:action place-both
    :parameters (?d - dualconf
                 ?a1 - arm ?o1 - obj ?p1 - pose ?g1 - grasp ?q1 - armconf
                 ?a2 - arm ?o2 - obj ?p2 - pose ?g2 - grasp ?q2 - armconf)
    :precondition (and (not (= ?a1 ?a2)) (not (= ?o1 ?o2)) (atdualconf ?d)
                       (confin ?d ?a1 ?q1) (kin ?a1 ?o1 ?p1 ?g1 ?q1) (holding ?a1 ?o1 ?g1)
                       (confin ?d ?a2 ?q2) (kin ?a2 ?o2 ?p2 ?g2 ?q2) (holding ?a2 ?o2 ?g2)
                       (not (unsafe ?o1 ?p1)) (not (unsafe ?o2 ?p2)) (cfree ?o1 ?p1 ?o2 ?p2))
    :effect (and (atpose ?o1 ?p1) (empty ?a1) (not (holding ?a1 ?o1 ?g1))
                 (atpose ?o2 ?p2) (empty ?a2) (not (holding ?a2 ?o2 ?g2))
                 (increase (total-cost) (gripper-time)))))
