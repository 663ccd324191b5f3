"""Planners over the language: classical search and the stream planning algorithms.

Kept light: import ``solvers.classical`` or :func:`solvers.solve.solve` for the machinery.
"""
