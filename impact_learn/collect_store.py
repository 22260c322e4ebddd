"""Where ``impact-collect`` writes: ``OUT.partial`` until every demo is stored, then ``OUT``."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import zarr

from impact_control.errors import InvalidArgumentError
from impact_learn.collect_config import CollectConfig
from impact_learn.dataset import FieldDims, ReplayWriter


def partial_path(out: str | Path) -> Path:
    """Where a collection writes until it is complete: ``OUT.partial``."""
    return Path(f"{out}.partial")


def _leftover(work: Path) -> int | None:
    """Complete episodes in ``OUT.partial`` when it is a store of an earlier run of ours (0 for
    one torn at creation: metadata files only), None when it is something else."""
    if not work.is_dir() or work.is_symlink():
        return None
    files = [p for p in work.rglob("*") if not p.is_dir()]
    if all(p.name == "zarr.json" for p in files):
        return 0  # empty, or torn while being created: no data to lose
    try:
        root = zarr.open_group(str(work), mode="r")
        if "format_version" not in root.attrs:
            return None
        return int(root["meta/episode_ends"].shape[0])
    except (KeyError, OSError, ValueError, zarr.errors.BaseZarrError):
        return None


def open_writer(cfg: CollectConfig, obs_dims: FieldDims, attrs: dict) -> ReplayWriter:
    """The writer on ``OUT.partial`` (renamed to ``OUT`` when complete).

    A partial store without a complete episode (a run that failed early) is replaced; one
    holding episodes is continued by ``--resume`` and otherwise refused, as is an
    ``OUT.partial`` that is not a store of ours (never removed). ``--resume`` on a finished
    ``OUT`` checks it (every chunk against its checksum), then moves it back to
    ``OUT.partial`` to append. A location that cannot be written is a one-line error."""
    final, work = Path(cfg.out), partial_path(cfg.out)
    try:
        if work.exists() and not cfg.resume:
            _replace_leftover(work)
        if final.exists():
            if not cfg.resume:
                raise InvalidArgumentError(f"{final} exists; pass --resume to append or remove it")
            if work.exists():
                raise InvalidArgumentError(f"both {final} and {work} exist; delete one of them")
            ReplayWriter(final, obs_dims, attrs, append=True)  # checks everything, or refuses
            os.replace(final, work)
            return ReplayWriter(work, obs_dims, attrs, append=True, verify=False)
        return ReplayWriter(work, obs_dims, attrs, append=cfg.resume)
    except OSError as exc:
        raise InvalidArgumentError(f"cannot write {work}: {exc.strerror or exc}; valid: an "
                                   "--out in a writable folder") from None


def _replace_leftover(work: Path) -> None:
    """Remove an ``OUT.partial`` left without episodes by an earlier run; refuse anything
    else (one holding episodes, or not a store of ours)."""
    n = _leftover(work)
    if n is None:
        raise InvalidArgumentError(
            f"{work} exists and is not a store of an unfinished impact-collect run; remove it "
            "or give another --out")
    if n:
        raise InvalidArgumentError(
            f"{work} holds {n} episodes of an unfinished run; pass --resume to continue it "
            "or delete it")
    shutil.rmtree(work)
