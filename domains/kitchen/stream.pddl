; Where the robot may stand to work at a station, and what moving between two places costs.
(define (stream kitchen)
  (:stream sample-conf
    :inputs (?s) :domain (station ?s)
    :outputs (?q) :certified (and (conf ?q) (reaches ?q ?s)))
  (:function (Distance ?q1 ?q2) (and (conf ?q1) (conf ?q2))))
