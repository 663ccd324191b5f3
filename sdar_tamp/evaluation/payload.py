"""An instance and the files it refers to, carried as text to a machine without the suite.

A Ray node need not share a disk with the driver: each task carries the instance file's text
and, when the instance names its own scene (``scene:``), the scene file's text and the robot
description the scene names. :func:`pack` reads them on the driver, :func:`unpack` writes them
into a folder on the node with the same relative layout, so relative references still resolve.
A robot description that refers to further files (meshes) needs them on the node at the path
it names.
"""

from __future__ import annotations

import atexit
import functools
import hashlib
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

from sdar_tamp.errors import SdarError
from sdar_tamp.textfile import read_text


class PayloadError(SdarError):
    """An instance whose files cannot be carried to another machine."""


@dataclass(frozen=True)
class InstanceFiles:
    """The text of an instance file and of the files it refers to.

    ``files``: (relative POSIX path, text) pairs, the instance file's at ``instance``."""

    instance: str
    files: tuple[tuple[str, str], ...]

    def digest(self) -> str:
        """SHA-256 over every path and text (hex): equal files, equal digest."""
        h = hashlib.sha256()
        for name, text in sorted(self.files):
            h.update(f"{len(name)}:{name}{len(text)}:".encode())
            h.update(text.encode("utf-8"))
        return h.hexdigest()


def pack(instance_path: Path) -> InstanceFiles:
    """The instance file at ``instance_path`` with its scene file and the scene's robot
    description (none for the shipped scene). Raises :class:`PayloadError` for a scene named
    by an absolute path (a node could not find it)."""
    from sdar_tamp.world.instance import load_instance
    from sdar_tamp.world.scene import load_scene

    path = Path(instance_path).resolve()
    paths = [path]
    instance = load_instance(path)
    if instance.scene is not None:
        if Path(instance.scene).is_absolute():
            raise PayloadError(
                f"{instance_path}: scene {instance.scene!r} is an absolute path; to carry the "
                "instance to another machine, name the scene relative to the instance file"
            )
        scene = instance.scene_path(path)
        assert scene is not None
        urdfs = dict.fromkeys(arm.urdf.resolve() for arm in load_scene(scene).arms)
        paths += [scene.resolve(), *urdfs]
    base = Path(os.path.commonpath([p.parent for p in paths]))
    files = tuple((p.relative_to(base).as_posix(), read_text(p)) for p in paths)
    return InstanceFiles(files[0][0], files)


@functools.cache
def _scratch() -> Path:
    """A folder of this process, removed when the process ends normally."""
    folder = Path(tempfile.mkdtemp(prefix="sdar-bench-"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    return folder


def unpack(files: InstanceFiles, root: Path | None = None) -> Path:
    """Write ``files`` under ``root`` (default: a folder of this process, one subfolder per
    :meth:`InstanceFiles.digest`, so the same files get the same path and the world built
    for a scene is reused); returns the instance file's path."""
    folder = (root if root is not None else _scratch()) / files.digest()[:32]
    for name, text in files.files:
        relative = PurePosixPath(name)
        if relative.is_absolute() or ".." in relative.parts:
            raise PayloadError(f"{name!r}: expected a relative path inside the instance folder")
        target = folder.joinpath(*relative.parts)
        if target.exists():
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        partial = target.with_name(f".{target.name}.partial")
        partial.write_text(text, encoding="utf-8")
        os.replace(partial, target)
    return folder.joinpath(*PurePosixPath(files.instance).parts)
