; Stable poses on a grid (a finite sampler) and the interval overlap test.
(define (stream narrow-region)
  (:stream sample-pose
    :inputs (?b ?r) :domain (and (block ?b) (region ?r))
    :outputs (?p) :certified (and (pose ?p) (blockpose ?b ?p) (contained ?b ?p ?r)))
  (:stream test-cfree
    :inputs (?b ?p ?b2 ?p2) :domain (and (blockpose ?b ?p) (blockpose ?b2 ?p2))
    :certified (cfree ?b ?p ?b2 ?p2)))
