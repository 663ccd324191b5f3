"""Geometric streams of the dual-arm rearrangement domain, each one swappable.

The public surface is re-exported lazily by the submodules; import what you need, e.g.
``from streams.motion.ladder import plan_dual_motion`` or ``from streams.stream_map import
make_stream_map``. Importing this package loads nothing heavy.
"""
