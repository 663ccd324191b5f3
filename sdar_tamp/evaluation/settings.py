"""The settings record of a benchmark folder (``settings.json``): what its rows depend on.

A row of ``results.csv`` is the outcome of one (instance, combination) pair *under* a seed, a
time limit, a number of parallel workers (they share the cores, so planning times and even
successes within the time limit depend on it), the backend that ran it (local processes or
Ray), the shard of the sweep the folder holds, the instance file's content and the package
version. The first run writes these to ``settings.json``; a rerun reuses rows only when its
own settings are the same, and otherwise stops with one line naming every difference (rather
than silently mixing outcomes of different settings). Instances added by a later run are
added to the record; an instance file whose content changed is a difference.

The optional packages that change plans are part of the record too: SDAR-M's first rung
warm-starts the optimiser from a sampled path where OMPL is installed (``extras``, e.g.
``{"ompl": "2.0.1"}``; a missing package is ``"none"``), so a rerun on a machine without it
would otherwise mix two motion ladders in one table.

A folder written before the record existed is checked against the seed and time limit its
rows hold, then gets a record. A record written before ``backend`` and ``shard`` existed
reads as the process backend, unsharded; one written before ``extras`` existed does not know
them, and they are not compared.
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import importlib.util
import json
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from sdar_tamp.errors import SdarError

SETTINGS = "settings.json"
FORMAT = 1
#: Optional packages whose presence changes plans (distribution name, import name).
PLAN_EXTRAS: tuple[tuple[str, str], ...] = (("ompl", "ompl"),)


class SettingsMismatch(SdarError):
    """A rerun's settings differ from those that made the rows already in the folder."""


@dataclass(frozen=True)
class BenchSettings:
    """Everything a benchmark row depends on besides its (instance, combination) pair.

    ``suite``: a shipped suite name or the resolved path of a folder; ``time_limit_s`` [s];
    ``workers``: runs at once (0: one per CPU of the Ray cluster); ``backend``: ``process``
    or ``ray``; ``shard``: ``"i/N"`` for one shard of a sweep, ``""`` for all of it;
    ``instances``: instance name -> SHA-256 of its file; ``extras``: optional package ->
    its version or ``"none"`` (:func:`plan_extras`; empty: not recorded)."""

    version: str
    suite: str
    seed: int
    time_limit_s: float
    workers: int
    instances: Mapping[str, str] = field(default_factory=dict)
    backend: str = "process"
    shard: str = ""
    extras: Mapping[str, str] = field(default_factory=dict)
    #: The scene file replacing the instances' own (its path and content digest), or "".
    scene: str = ""

    def to_json(self) -> dict[str, Any]:
        return dict(
            format=FORMAT, version=self.version, suite=self.suite, seed=self.seed,
            time_limit_s=self.time_limit_s, workers=self.workers, backend=self.backend,
            shard=self.shard, extras=dict(sorted(self.extras.items())), scene=self.scene,
            instances=dict(sorted(self.instances.items())),
        )  # fmt: skip


def plan_extras() -> dict[str, str]:
    """The installed version of every optional package that changes plans
    (:data:`PLAN_EXTRAS`), ``"none"`` for one that is not importable."""
    found = {}
    for dist, module in PLAN_EXTRAS:
        version = "none"
        if importlib.util.find_spec(module) is not None:
            try:
                version = importlib.metadata.version(dist)
            except importlib.metadata.PackageNotFoundError:
                version = "unknown version"
        found[dist] = version
    return found


def file_digest(path: Path) -> str:
    """SHA-256 of a file's bytes (hex)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def read_settings(out_dir: Path) -> BenchSettings | None:
    """The record in ``out_dir``, ``None`` if there is none. Raises :class:`SdarError` for a
    file that is not a record of this format."""
    path = Path(out_dir) / SETTINGS
    if not path.exists():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        if data.get("format") != FORMAT:
            raise ValueError(f"format {data.get('format')!r}")
        return BenchSettings(
            version=str(data["version"]), suite=str(data["suite"]), seed=int(data["seed"]),
            time_limit_s=float(data["time_limit_s"]), workers=int(data["workers"]),
            instances={str(k): str(v) for k, v in dict(data["instances"]).items()},
            backend=str(data.get("backend", "process")), shard=str(data.get("shard", "")),
            extras={str(k): str(v) for k, v in dict(data.get("extras", {})).items()},
            scene=str(data.get("scene", "")),
        )  # fmt: skip
    except (ValueError, KeyError, TypeError, AttributeError) as error:
        raise SdarError(
            f"{path}: not a settings record of format {FORMAT} ({error}); "
            "delete it only if the rows beside it were made with the current settings"
        ) from None


def write_settings(out_dir: Path, settings: BenchSettings) -> Path:
    """Write the record (atomically: a reader sees the old or the new one)."""
    path = Path(out_dir) / SETTINGS
    partial = path.with_name(f".{SETTINGS}.partial")
    partial.write_text(json.dumps(settings.to_json(), indent=1) + "\n", encoding="utf-8")
    os.replace(partial, path)
    return path


def _limit(value: float) -> str:
    return f"{value:g} s"


def _workers(value: int) -> str:
    return str(value) if value else "one per cluster CPU"


def _shard(value: str) -> str:
    return value or "none"


def differences(old: BenchSettings, new: BenchSettings, *, shard: bool = True) -> list[str]:
    """What differs between two records (one phrase each), ``shard`` included unless told
    otherwise; an instance counts only when both records hold it with other contents."""
    pairs = [
        ("version", old.version, new.version),
        ("suite", old.suite, new.suite),
        ("seed", str(old.seed), str(new.seed)),
        ("time limit", _limit(old.time_limit_s), _limit(new.time_limit_s)),
        ("workers", _workers(old.workers), _workers(new.workers)),
        ("backend", old.backend, new.backend),
        ("scene", old.scene or "the instances' own", new.scene or "the instances' own"),
    ]
    if shard:
        pairs.append(("shard", _shard(old.shard), _shard(new.shard)))
    if old.extras and new.extras:  # an older record does not know them
        for name in sorted(set(old.extras) | set(new.extras)):
            then, now = old.extras.get(name, "none"), new.extras.get(name, "none")
            pairs.append((name, then, now))
    found = [f"{name} {now} (the rows: {then})" for name, then, now in pairs if then != now]
    found += [
        f"instance {name} (file changed since its rows)"
        for name, digest in new.instances.items()
        if old.instances.get(name, digest) != digest
    ]
    return found


def _row_differences(rows: Sequence[Mapping[str, str]], new: BenchSettings) -> list[str]:
    """Seed and time limit of rows written without a record (older versions)."""
    found = []
    seeds = sorted({r["seed"] for r in rows}, key=lambda s: (len(s), s))
    if seeds != [str(new.seed)]:
        found.append(f"seed {new.seed} (the rows: {', '.join(seeds)})")
    limits = sorted({float(r["time_limit_s"]) for r in rows})
    if limits != [float(f"{new.time_limit_s:.6g}")]:  # the rows hold 6 significant digits
        found.append(
            f"time limit {_limit(new.time_limit_s)} (the rows: {', '.join(map(_limit, limits))})"
        )
    return found


def reconcile(
    out_dir: Path, new: BenchSettings, rows: Iterable[Mapping[str, str]]
) -> BenchSettings:
    """The record to keep in ``out_dir`` for a run with settings ``new`` that finds ``rows``
    there: ``new`` with every instance of the old record. Raises :class:`SettingsMismatch`
    (one line) if the rows were made with other settings."""
    rows = list(rows)
    if not rows:  # nothing to protect: a fresh start
        return new
    old = read_settings(out_dir)
    if old is None:
        found = _row_differences(rows, new)
        merged = new
    else:
        found = differences(old, new)
        merged = replace(new, instances={**old.instances, **new.instances})
    if found:
        raise SettingsMismatch(
            f"{out_dir} holds runs made with other settings: {'; '.join(found)}. Rerun with "
            "the settings of the rows, pass --restart to discard them, or use another --out"
        )
    return merged
