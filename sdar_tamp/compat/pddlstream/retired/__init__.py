"""``pddlstream.retired``: the retired entry points some examples still import."""

__all__: list[str] = []
