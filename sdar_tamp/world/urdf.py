"""Reading a robot description (URDF): mesh URIs resolved, located errors.

A URDF names its meshes by ``package://<package>/<path>`` URIs (as ROS tools do), by
``file://`` URIs or by paths relative to the URDF file. :func:`read_urdf` returns the text with
every collision mesh's ``filename`` made an absolute path, so pinocchio and coal load the
meshes whatever the working directory. A package is looked up in the package directories the
scene names, then in those of ``ROS_PACKAGE_PATH`` (see :func:`package_dirs_from_env`): a
directory whose own name is the package, or a directory holding a folder of that name.
Everything that goes wrong raises :class:`~sdar_tamp.world.errors.SceneError` at the URDF's
``file:line:col``.
"""

from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from pathlib import Path

from sdar_tamp.errors import SourceLocation
from sdar_tamp.textfile import read_text
from sdar_tamp.world._yaml import file_error
from sdar_tamp.world.errors import SceneError

#: The environment variable listing package directories, as ROS 1 tools read it.
PACKAGE_PATH_VARIABLE = "ROS_PACKAGE_PATH"

#: The collision shapes pinocchio reads from a URDF (it drops others with a printed warning).
SHAPES = ("box", "cylinder", "sphere", "mesh")
_SHAPE = re.compile(
    r"<collision\b[^>]*>(?:(?!</collision>).)*?<geometry\b[^>]*>\s*(?:<!--.*?-->\s*)*<(\w+)",
    re.DOTALL,
)
_COLLISION = re.compile(r"<collision\b.*?</collision>", re.DOTALL)
_FILENAME = re.compile(r"""(<mesh\b[^>]*?\bfilename\s*=\s*)(["'])(.*?)\2""", re.DOTALL)


def package_dirs_from_env(environ: Mapping[str, str] | None = None) -> tuple[Path, ...]:
    """The directories of ``ROS_PACKAGE_PATH`` (``os.pathsep``-separated; empty entries
    skipped) in ``environ`` (default ``os.environ``)."""
    env = os.environ if environ is None else environ
    value = env.get(PACKAGE_PATH_VARIABLE, "")
    return tuple(Path(p) for p in value.split(os.pathsep) if p.strip())


def example_robot_data_share(environ: Mapping[str, str] | None = None) -> Path | None:
    """The ``share`` folder holding ``example-robot-data/robots`` (the optional extra
    ``robots``): ``EXAMPLE_ROBOT_DATA_SHARE`` of ``environ`` (default ``os.environ``) if it
    names one, else the installed package's (a pip install puts it under ``cmeel.prefix``);
    ``None`` when it is not installed."""
    import site
    import sys

    env = os.environ if environ is None else environ
    given = env.get("EXAMPLE_ROBOT_DATA_SHARE")
    roots = [Path(given)] if given else []
    for prefix in [*site.getsitepackages(), sys.prefix]:
        roots += [Path(prefix) / "cmeel.prefix" / "share", Path(prefix) / "share"]
    return next((r for r in roots if (r / "example-robot-data" / "robots").is_dir()), None)


def resolve_package_uri(uri: str, package_dirs: tuple[Path, ...]) -> Path | None:
    """The file a ``package://<package>/<path>`` URI names, or ``None`` when no directory of
    ``package_dirs`` (in order) holds it."""
    rest = uri[len("package://") :]
    package, _, relative = rest.partition("/")
    if not package or not relative:
        return None
    for directory in package_dirs:
        for root in (directory, directory / package):
            if root.name != package:
                continue
            candidate = root / relative
            if candidate.is_file():
                return candidate.resolve()
    return None


def resolve_uri(
    uri: str, base_dir: Path, package_dirs: tuple[Path, ...]
) -> tuple[Path | None, str]:
    """The file ``uri`` names (``package://``, ``file://`` or a path, relative to
    ``base_dir``) and how it was looked up (for an error message), or ``None`` if missing."""
    if uri.startswith("package://"):
        searched = ", ".join(str(d) for d in package_dirs) or "none given"
        return resolve_package_uri(uri, package_dirs), f"package directories: {searched}"
    path = Path(uri[len("file://") :] if uri.startswith("file://") else uri)
    path = path if path.is_absolute() else base_dir / path
    return (path.resolve() if path.is_file() else None), f"looked for {path}"


def _location(file: Path, text: str, offset: int) -> SourceLocation:
    line = text.count("\n", 0, offset) + 1
    column = offset - (text.rfind("\n", 0, offset) + 1) + 1
    return SourceLocation(str(file), line, column)


def read_urdf(urdf: Path, package_dirs: tuple[Path, ...] = ()) -> str:
    """The text of the URDF at ``urdf`` with every collision mesh's ``filename`` an absolute
    path (visual meshes are left as they are: the planner and the validator do not read them).

    Raises:
        SceneError: the file cannot be read, is not well-formed XML, has no ``<robot>`` root,
            has a shape pinocchio does not read (at the shape's tag), or names a mesh that
            cannot be found (at the ``filename`` attribute).
    """
    text = read_text(urdf, file_error(SceneError))
    try:
        root = ET.fromstring(text)
    except ET.ParseError as error:
        line, column = error.position
        message = str(error).split(":")[0]
        raise SceneError(
            f"not a well-formed robot description: {message}",
            SourceLocation(str(urdf), line, column + 1),
        ) from None
    if root.tag != "robot":
        raise SceneError(
            f"expected a <robot> root element, got <{root.tag}>", SourceLocation(str(urdf), 1, 1)
        )
    for match in _SHAPE.finditer(text):
        if match.group(1) not in SHAPES:
            raise SceneError(
                f"a collision shape {match.group(1)!r}; the supported shapes are "
                f"{', '.join(SHAPES)}",
                _location(urdf, text, match.start(1)),
            )
    base_dir = urdf.parent

    def collision(block: re.Match[str]) -> str:
        def absolute(match: re.Match[str]) -> str:
            uri = match.group(3).strip()
            path, how = resolve_uri(uri, base_dir, package_dirs)
            if path is None:
                where = _location(urdf, text, block.start() + match.start(3))
                raise SceneError(f"mesh {uri!r} not found ({how})", where)
            return f"{match.group(1)}{match.group(2)}{path}{match.group(2)}"

        return _FILENAME.sub(absolute, block.group(0))

    return _COLLISION.sub(collision, text)
