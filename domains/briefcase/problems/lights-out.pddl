; Switch every light off and end in the hall. The study's switch is in the kitchen and the
; kitchen's in the study, so the torch in the kitchen is needed to walk back in the dark.
(define (problem lights-out)
  (:domain briefcase)
  (:objects hall kitchen study - room torch - lamp)
  (:init (case-at hall)
         (door hall kitchen) (door hall study)
         (light-on kitchen) (light-on study) (light-on hall)
         (switch hall hall) (switch kitchen study) (switch study kitchen)
         (at torch kitchen))
  (:goal (and (case-at hall) (not (exists (?r - room) (light-on ?r))))))
