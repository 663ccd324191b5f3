"""Fitted sphere models kept on disk, so that a process does not fit a robot's meshes again.

A model is stored as ``spheres-<key>.npz`` in the cache folder of the compiled derivatives
(:func:`streams.motion.codegen.cache_dir`: ``$SDAR_TAMP_CACHE``, else
``$XDG_CACHE_HOME/sdar-tamp``, else ``~/.cache/sdar-tamp``; never the working directory). The
key is a hash of the robot description's content (:func:`streams.motion.spheres.model_digest`),
the parameters of the fit and :data:`VERSION`. ``SDAR_TAMP_SPHERE_CACHE=0`` (or ``false``,
``no``, ``off``) turns it off. A file is written beside its target and appears by one atomic
rename; a file that cannot be read or written is skipped (the model is fitted), never an error.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from pathlib import Path

import numpy as np

from sdar_tamp.logs import get_logger
from sdar_tamp.world.transforms import FloatArray
from streams.motion.codegen import cache_dir

ENV_SWITCH = "SDAR_TAMP_SPHERE_CACHE"
#: Changes whenever the fit would give other spheres for the same input.
VERSION = "2"

_log = get_logger(__name__)

Arrays = tuple[np.ndarray, FloatArray, FloatArray]  # joint (n,), centre (n, 3), radius (n,)


def enabled() -> bool:
    """False when ``SDAR_TAMP_SPHERE_CACHE`` is ``0``, ``false``, ``no`` or ``off``."""
    return os.environ.get(ENV_SWITCH, "1").strip().lower() not in {"0", "false", "no", "off"}


def cache_key(*parts: object) -> str:
    """A hash of :data:`VERSION` and ``parts`` (their ``repr``)."""
    text = "\n".join([VERSION, *(repr(p) for p in parts)])
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:32]


def cache_path(key: str) -> Path:
    return cache_dir() / f"spheres-{key}.npz"


def load(key: str) -> Arrays | None:
    """The model stored under ``key``, or None (none stored, unreadable, or the cache off)."""
    path = cache_path(key)
    if not enabled() or not path.is_file():
        return None
    try:
        with np.load(path) as data:
            joint, centre, radius = data["joint"], data["centre"], data["radius"]
    except (OSError, ValueError, KeyError) as error:
        _log.info("sphere model %s unreadable, fitted again: %s", path, error)
        return None
    n = len(radius)
    if joint.shape != (n,) or centre.shape != (n, 3):
        _log.info("sphere model %s malformed, fitted again", path)
        return None
    return joint.astype(np.int64), centre.astype(np.float64), radius.astype(np.float64)


def store(key: str, joint: np.ndarray, centre: FloatArray, radius: FloatArray) -> None:
    """Keep a model under ``key`` (nothing when the cache is off or cannot be written)."""
    if not enabled():
        return
    path = cache_path(key)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=path.stem, suffix=".tmp", dir=path.parent)
        with os.fdopen(fd, "wb") as out:
            np.savez(out, joint=joint, centre=centre, radius=radius)
        os.replace(tmp, path)
    except OSError as error:
        _log.info("sphere model not kept in %s: %s", path.parent, error)
