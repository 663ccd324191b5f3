"""Errors raised by the dual-arm world: one subclass of :class:`SdarError` per concern."""

from __future__ import annotations

from sdar_tamp.errors import LocatedError, SdarError, SourceLocation


class WorldError(SdarError):
    """Base class of every error of :mod:`sdar_tamp.world`."""


class WorldFileError(WorldError, LocatedError):
    """A scene, instance or suite file (or its parsed value) is malformed.

    The message reads ``file:line:col: key.path: expected ..., got ...``.
    """

    def __init__(self, message: str, location: SourceLocation | None = None) -> None:
        LocatedError.__init__(self, message, location)


class SceneError(WorldFileError):
    """A bad scene file (``scene.yaml``)."""


class InstanceError(WorldFileError):
    """A bad rearrangement instance: file shape, or a geometric rule an object breaks."""


class SuiteError(WorldFileError):
    """An unknown suite name or a bad suite directory."""


class KinematicsError(WorldError):
    """A kinematic query that cannot be answered (bad shape, unknown frame or arm)."""


class CollisionModelError(WorldError):
    """A bad request to the collision world (unknown arm or object, object already held)."""


class GenerationError(WorldError):
    """A seeded generator could not build the structure it promises within its retry budget."""


class ArmLayoutError(WorldError, ValueError):
    """A bad arm layout (no arms, repeated names, a non-positive DoF) or a configuration
    whose shape does not match the layout, or an arm the layout does not have."""


class ObservedStateError(WorldFileError):
    """A bad observed-state file, or an observed arrangement that cannot be (two objects
    overlapping, an object inside an arm, off the workspace, an unknown object)."""
