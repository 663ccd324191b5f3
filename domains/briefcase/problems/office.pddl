; Fetch two documents into the office; the cellar is dark, the lamp is in the hall.
(define (problem office)
  (:domain briefcase)
  (:objects home hall office cellar - room
            letter contract - document
            torch - lamp)
  (:init (case-at home)
         (door home hall) (door hall office) (door hall cellar)
         (light-on home) (light-on hall) (light-on office)
         (switch home hall) (switch hall office) (switch office home)
         (at torch hall) (at letter home) (at contract cellar))
  (:goal (and (forall (?d - document) (at ?d office))
              (forall (?r - room) (dark ?r))
              (not (in letter)) (not (in contract)))))
