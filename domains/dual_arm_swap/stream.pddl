; Buffer poses for an object, the reach test of an arm, and the object-object overlap test.
(define (stream dual-arm-swap)
  (:stream sample-buffer
    :inputs (?o) :domain (obj ?o)
    :outputs (?p) :certified (and (pose ?p) (objpose ?o ?p) (buffer ?p)))
  (:stream test-reach
    :inputs (?a ?p) :domain (and (arm ?a) (pose ?p))
    :certified (reachable ?a ?p))
  (:stream test-cfree
    :inputs (?o ?p ?o2 ?p2) :domain (and (objpose ?o ?p) (objpose ?o2 ?p2))
    :certified (cfree ?o ?p ?o2 ?p2)))
