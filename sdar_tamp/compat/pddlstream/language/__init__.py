"""``pddlstream.language``: the modules a PDDLStream program imports its language from."""

__all__: list[str] = []
