"""``pddlstream.retired``: the retired entry points some examples still import."""
