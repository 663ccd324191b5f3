; A 2-D (side view) pick-and-place world: blocks are rectangles standing on a table line,
; regions are intervals of the table, the robot is a gripper that moves along sampled
; trajectories. Every geometric fact comes from a stream (see stream.pddl).
(define (domain pick-place-2d)
  (:requirements :strips :typing :equality :negative-preconditions :derived-predicates
                 :existential-preconditions :action-costs)
  (:types block region pose grasp conf traj)
  (:predicates
    (blockpose ?b - block ?p - pose)                ; ?p is a stable pose of ?b
    (blockgrasp ?b - block ?g - grasp)              ; ?g is a grasp of ?b
    (contained ?b - block ?p - pose ?r - region)    ; ?b at ?p lies inside ?r
    (kin ?b - block ?p - pose ?g - grasp ?q - conf) ; the gripper at ?q holds ?b at ?p by ?g
    (freemotion ?q1 - conf ?t - traj ?q2 - conf)    ; ?t moves the empty gripper ?q1 -> ?q2
    (holdingmotion ?q1 - conf ?t - traj ?q2 - conf ?b - block ?g - grasp)
    (cfree ?b - block ?p - pose ?b2 - block ?p2 - pose)  ; the two blocks do not overlap
    (trajcollision ?t - traj ?b2 - block ?p2 - pose) ; ?t sweeps through ?b2 standing at ?p2
    (atpose ?b - block ?p - pose) (atgrasp ?b - block ?g - grasp) (atconf ?q - conf)
    (handempty)
    (in ?b - block ?r - region)
    (unsafepose ?b - block ?p - pose)
    (unsafetraj ?t - traj))
  (:functions (total-cost))

  (:derived (in ?b - block ?r - region)
    (exists (?p - pose) (and (contained ?b ?p ?r) (atpose ?b ?p))))
  (:derived (unsafepose ?b - block ?p - pose)
    (exists (?b2 - block ?p2 - pose)
      (and (blockpose ?b ?p) (atpose ?b2 ?p2) (not (= ?b ?b2)) (not (cfree ?b ?p ?b2 ?p2)))))
  (:derived (unsafetraj ?t - traj)
    (exists (?b2 - block ?p2 - pose) (and (atpose ?b2 ?p2) (trajcollision ?t ?b2 ?p2))))

  (:action move-free
    :parameters (?q1 - conf ?t - traj ?q2 - conf)
    :precondition (and (freemotion ?q1 ?t ?q2) (atconf ?q1) (handempty) (not (unsafetraj ?t)))
    :effect (and (atconf ?q2) (not (atconf ?q1)) (increase (total-cost) 1)))
  (:action move-holding
    :parameters (?q1 - conf ?t - traj ?q2 - conf ?b - block ?g - grasp)
    :precondition (and (holdingmotion ?q1 ?t ?q2 ?b ?g) (atconf ?q1) (atgrasp ?b ?g)
                       (not (unsafetraj ?t)))
    :effect (and (atconf ?q2) (not (atconf ?q1)) (increase (total-cost) 1)))
  (:action pick
    :parameters (?b - block ?p - pose ?g - grasp ?q - conf)
    :precondition (and (kin ?b ?p ?g ?q) (atpose ?b ?p) (handempty) (atconf ?q))
    :effect (and (atgrasp ?b ?g) (not (atpose ?b ?p)) (not (handempty))
                 (increase (total-cost) 1)))
  (:action place
    :parameters (?b - block ?p - pose ?g - grasp ?q - conf)
    :precondition (and (kin ?b ?p ?g ?q) (atgrasp ?b ?g) (atconf ?q) (not (unsafepose ?b ?p)))
    :effect (and (atpose ?b ?p) (handempty) (not (atgrasp ?b ?g))
                 (increase (total-cost) 1))))
