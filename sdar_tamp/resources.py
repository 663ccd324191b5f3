"""Locate the files shipped under ``domains/`` (works from a checkout and an installed wheel)."""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

from sdar_tamp.errors import ParameterError


def domains_root() -> Path:
    """The folder holding one sub-folder per shipped domain."""
    return Path(str(files("domains")))


def shipped_domains() -> tuple[str, ...]:
    root = domains_root()
    return tuple(
        sorted(p.name for p in root.iterdir() if p.is_dir() and (p / "domain.pddl").is_file())
    )


def domain_file(domain: str, name: str = "domain.pddl") -> Path:
    """The path of ``name`` inside the shipped domain folder ``domain``.

    Raises:
        ParameterError: the domain or the file does not exist (the message lists what does).
    """
    folder = domains_root() / domain
    if not folder.is_dir():
        raise ParameterError(
            f"domain must be one of {', '.join(shipped_domains())}; got {domain!r}"
        )
    path = folder / name
    if not path.is_file():
        available = sorted(str(p.relative_to(folder)) for p in folder.rglob("*.pddl"))
        raise ParameterError(f"{domain}/{name} does not exist; files: {', '.join(available)}")
    return path
