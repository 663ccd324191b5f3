; One package from a house in city 1 to a house in city 2.
(define (problem two-cities)
  (:domain logistics)
  (:objects
    c1 c2 - city
    house1 house2 - location
    port1 port2 - airport
    truck1 truck2 - truck
    plane - airplane
    parcel - package)
  (:init
    (in-city house1 c1) (in-city port1 c1)
    (in-city house2 c2) (in-city port2 c2)
    (at truck1 house1) (at truck2 port2) (at plane port1)
    (at parcel house1))
  (:goal (at parcel house2)))
