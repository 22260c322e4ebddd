"""Keep numba's on-disk kernel cache consistent with the kernel sources.

Numba's ``cache=True`` keys a compiled function on the timestamp of the file that *defines*
it. A cached function that calls (and inlines) a kernel from another module is therefore
loaded stale after only that other module changed: e.g. ``loop/tick.py::loop_tick``, which
inlines the whole controller tick from ``control/kernels*.py``, kept running an old
controller after a stage kernel changed (numba documents this under "Cache
invalidation"). This module stamps each cache directory with a digest of *all* kernel sources
and deletes the kernel modules' cached functions there when the digest differs, so the next
call recompiles them. It runs on ``import impact_control`` for the controller's kernels and on
``import impact_envs`` for the simulation loop's, whose digest also covers the controller's
sources (file reads and a hash, ~2 ms each; numba is not imported).

Covered cache locations: numba's default in-tree ``__pycache__`` next to each source and, when
``NUMBA_CACHE_DIR`` is set, its mirror of the source directory there. A package installed
read-only falls back to numba's per-user cache; reinstalling rewrites every source file, which
invalidates that cache anyway.
"""

from __future__ import annotations

import hashlib
import os
import re
from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent
"""``impact_control``: every module of it may define ``@njit`` functions."""
NJIT_MARK = re.compile(rb"^@njit", re.MULTILINE)

STAMP_NAME = "impact_kernels.sha256"
"""File written into each cache directory: the digest its cached kernels were built from."""


def kernel_sources(folders: tuple[Path, ...] = (PACKAGE_DIR,)) -> list[Path]:
    """The kernel source files under ``folders``: every module with a line starting ``@njit``,
    found by reading the files (nothing imported), so a new stage module is covered without
    being listed anywhere."""
    return [path for path in digest_sources(folders) if NJIT_MARK.search(path.read_bytes())]


def digest_sources(folders: tuple[Path, ...] = (PACKAGE_DIR,)) -> list[Path]:
    """Every module under ``folders``, kernel modules or not: a cached kernel refers to the
    named tuples it takes by their module (``DynamicsArrays`` in control/arm_model.py,
    ``SimArrays`` in robot/sim.py, a stage's scalars in its config module), and constants it
    reads may live beside them, so changing any of these must invalidate the cache too. (Only
    modules with ``@njit`` lines were counted until 2026-11-27: a stage's type module without one
    left kernels cached against a class that no longer existed.)"""
    return [path for folder in folders for path in sorted(folder.rglob("*.py"))]


def sources_digest(sources: list[Path]) -> str:
    """SHA-256 over the sources' names and bytes (order-independent)."""
    h = hashlib.sha256()
    for path in sorted(sources, key=lambda p: p.name):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def cache_dirs(source: Path) -> list[Path]:
    """Where numba may cache functions defined in ``source``."""
    dirs = [source.parent / "__pycache__"]
    user_dir = os.environ.get("NUMBA_CACHE_DIR")
    if user_dir:
        parent = source.parent.resolve()
        dirs.append(Path(user_dir) / parent.relative_to(parent.anchor))
    return dirs


def refresh_cache(sources: list[Path], digest: str) -> int:
    """Delete the cached kernels of ``sources`` in every cache directory whose stamp is not
    ``digest``, then stamp it; returns the number of files deleted. A missing directory is
    created and stamped (numba fills it next); one that cannot be written is skipped (numba
    cannot cache there either)."""
    by_dir: dict[Path, list[str]] = {}
    for src in sources:
        for d in cache_dirs(src):
            by_dir.setdefault(d, []).append(src.stem)
    deleted = 0
    for d, stems in by_dir.items():
        stamp = d / STAMP_NAME
        try:
            d.mkdir(parents=True, exist_ok=True)
            if stamp.is_file() and stamp.read_text().strip() == digest:
                continue
            for stem in stems:
                for f in [*d.glob(f"{stem}.*.nbi"), *d.glob(f"{stem}.*.nbc")]:
                    f.unlink(missing_ok=True)
                    deleted += 1
            stamp.write_text(digest + "\n")
        except OSError:
            continue
    return deleted


def ensure_fresh_kernel_cache(folders: tuple[Path, ...] = (PACKAGE_DIR,),
                              depends_on: tuple[Path, ...] = ()) -> int:
    """``refresh_cache`` for the kernel modules under ``folders``, with a digest over every
    module of ``folders`` and ``depends_on`` (the folders whose kernels they inline). Called
    on ``import impact_control`` with the defaults, and on ``import impact_envs`` for the
    simulation loop's folders, which depend on ``PACKAGE_DIR``."""
    digest = sources_digest(digest_sources((*folders, *depends_on)))
    return refresh_cache(kernel_sources(folders), digest)
