; Three cities, two airplanes, four packages going in different directions.
(define (problem three-cities)
  (:domain logistics)
  (:objects
    c1 c2 c3 - city
    h1 h2 h3 - location
    a1 a2 a3 - airport
    t1 t2 t3 - truck
    p1 p2 - airplane
    pkg1 pkg2 pkg3 pkg4 - package)
  (:init
    (in-city h1 c1) (in-city a1 c1)
    (in-city h2 c2) (in-city a2 c2)
    (in-city h3 c3) (in-city a3 c3)
    (at t1 h1) (at t2 a2) (at t3 h3)
    (at p1 a1) (at p2 a3)
    (at pkg1 h1) (at pkg2 h2) (at pkg3 a3) (at pkg4 h1))
  (:goal (and (at pkg1 h3) (at pkg2 a1) (at pkg3 h2) (at pkg4 h1))))
