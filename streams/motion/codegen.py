"""CasADi functions compiled to machine code, cached on disk, optional.

The optimiser's Jacobian and Hessian are SX functions that CasADi evaluates in its virtual
machine; compiled, the same expressions evaluate about ten times faster (the Hessian of the
12-DoF transfer: 4.2 ms -> 0.44 ms per call on one core), with the same values. Compiling
takes about 20 s of CPU with ``-O1``, so it is done once per distinct code: the library is
kept in the cache folder (:func:`cache_dir`) under a hash of the caller's *recipe* (a text
that changes whenever the generated code would), the flags, the compiler and the CasADi
version, where every later process finds it without generating any code; :func:`same_values`
checks a loaded library against CasADi's own evaluation.

Nothing here is required: without a C compiler (``$CC``, else ``cc``), with
``SDAR_TAMP_COMPILE=0``, or when anything fails, :func:`request` returns None and the caller
keeps CasADi's own evaluation. The compiler runs in a detached process (a short run does not
wait for it, and the library is there for the next one); it writes beside its target and the
library appears by one atomic rename; a lock file keeps a second process from compiling the
same code at once. Nothing is written to the working directory.
"""

from __future__ import annotations

import hashlib
import os
import shlex
import shutil
import subprocess
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from sdar_tamp.logs import get_logger
from streams.motion._casadi import ca

_log = get_logger(__name__)

#: ``-O1``: most of ``-O2``'s speed (0.44 vs 0.41 ms) at a seventh of its compile time.
FLAGS: tuple[str, ...] = ("-O1", "-shared", "-fPIC")
ENV_SWITCH = "SDAR_TAMP_COMPILE"
ENV_CACHE = "SDAR_TAMP_CACHE"
#: [s] after which a compile lock left behind (a killed compile) is taken over
STALE_LOCK = 600.0


def enabled() -> bool:
    """False when ``SDAR_TAMP_COMPILE`` is ``0``, ``false``, ``no`` or ``off``."""
    return os.environ.get(ENV_SWITCH, "1").strip().lower() not in {"0", "false", "no", "off"}


def cache_dir() -> Path:
    """``$SDAR_TAMP_CACHE``, else ``$XDG_CACHE_HOME/sdar-tamp``, else ``~/.cache/sdar-tamp``."""
    if os.environ.get(ENV_CACHE):
        return Path(os.environ[ENV_CACHE])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "sdar-tamp"


def compiler() -> str | None:
    """The C compiler's path (``$CC``, else ``cc``), or None when there is none."""
    return shutil.which(os.environ.get("CC", "cc"))


def source(functions: Sequence[ca.Function], name: str) -> str:
    """The C code of ``functions`` (one translation unit named ``name``)."""
    gen = ca.CodeGenerator(f"{name}.c", {"with_header": False})
    for fn in functions:
        gen.add(fn)
    text: str = gen.dump()
    return text


def library_path(recipe: str, folder: Path | None = None, flags: Sequence[str] = FLAGS) -> Path:
    """Where the library made from ``recipe`` is kept: named by a hash of the recipe (a text
    that changes whenever the functions' code would), the flags, the compiler and the CasADi
    version."""
    cc = compiler() or ""
    key = "\n".join([recipe, " ".join(flags), cc, ca.__version__])
    digest = hashlib.sha256(key.encode("utf-8")).hexdigest()[:24]
    return (folder or cache_dir()) / f"casadi-{digest}.so"


def request(
    functions: Sequence[ca.Function], name: str, recipe: str, flags: Sequence[str] = FLAGS
) -> Path | None:
    """The library of ``functions`` if it is in the cache (found by ``recipe``, no code is
    generated for that); otherwise their C code is generated and compiled in the background
    (unless compiling is off, there is no compiler, or another process is compiling it) and
    the library's future path is returned: it exists once the compile has finished. None
    when it will not be compiled. The recipe is a promise; :func:`same_values` is the proof
    a caller asks for before using a library."""
    if not enabled():
        return None
    target = library_path(recipe, flags=flags)
    if target.is_file():
        return target
    cc = compiler()
    if cc is None:
        _log.info("no C compiler (%s): %s stays uncompiled", os.environ.get("CC", "cc"), name)
        return None
    try:
        if start_compile(source(functions, name), target, cc, flags):
            _log.info("compiling %s in the background into %s", name, target)
    except OSError as error:
        _log.info("compiling %s is not possible, kept uncompiled: %s", name, error)
        return None
    return target


def start_compile(code: str, target: Path, cc: str, flags: Sequence[str] = FLAGS) -> bool:
    """Compile ``code`` into ``target`` in a detached process (it finishes even if this
    process exits first; the library appears by an atomic rename). False when another
    process holds the lock of ``target`` (taken over after :data:`STALE_LOCK` seconds)."""
    target.parent.mkdir(parents=True, exist_ok=True)
    lock = target.with_name(target.name + ".lock")
    try:
        fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except FileExistsError:
        if time.time() - lock.stat().st_mtime < STALE_LOCK:
            return False
        lock.unlink(missing_ok=True)
        fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    os.close(fd)
    work = Path(tempfile.mkdtemp(prefix="sdar-cc-"))
    src = work / "code.c"
    out = target.with_name(f".{target.name}.{os.getpid()}.tmp")  # same folder: atomic rename
    src.write_text(code, encoding="utf-8")
    command = [cc, *flags, str(src), "-o", str(out), "-lm"]
    script = (
        f"{shlex.join(command)} >/dev/null 2>&1 && mv -f {shlex.quote(str(out))} "
        f"{shlex.quote(str(target))}; rm -rf {shlex.quote(str(work))} {shlex.quote(str(lock))}"
    )
    subprocess.Popen(
        ["/bin/sh", "-c", script],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    return True


def load(functions: Sequence[ca.Function], library: Path) -> list[ca.Function]:
    """The compiled twins of ``functions`` from ``library`` (same names and signatures)."""
    return [ca.external(fn.name(), str(library)) for fn in functions]


def same_values(
    functions: Sequence[ca.Function], twins: Sequence[ca.Function], seed: int = 0
) -> bool:
    """Whether ``twins`` give the values of ``functions`` at one random point of their
    inputs (to 1e-9 relative); a compiled library that does not is not used."""
    rng = np.random.default_rng(seed)
    for fn, twin in zip(functions, twins, strict=True):
        if (fn.n_in(), fn.n_out()) != (twin.n_in(), twin.n_out()):
            return False
        args = [rng.uniform(-1.0, 1.0, (fn.size1_in(i), fn.size2_in(i))) for i in range(fn.n_in())]
        ours, theirs = fn.call(args), twin.call(args)
        for x, y in zip(ours, theirs, strict=True):
            u, v = np.asarray(ca.DM(x).full()), np.asarray(ca.DM(y).full())
            if u.shape != v.shape or not np.allclose(u, v, rtol=1e-9, atol=1e-12):
                return False
    return True
