; Reverse a tower of four blocks: d on c on b on a becomes a on b on c on d.
(define (problem reverse4)
  (:domain blocksworld)
  (:objects a b c d)
  (:init (on-table a) (on b a) (on c b) (on d c) (clear d) (hand-empty))
  (:goal (and (on a b) (on b c) (on c d))))
