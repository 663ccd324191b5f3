; The Sussman anomaly: C sits on A; build the tower A on B on C.
(define (problem sussman)
  (:domain blocksworld)
  (:objects a b c)
  (:init (on-table a) (on-table b) (on c a) (clear b) (clear c) (hand-empty))
  (:goal (and (on a b) (on b c))))
