"""``run.json``: provenance of a sweep (versions, git SHA, CLI, env spec, periods, wall times)."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
from dataclasses import asdict, dataclass
from datetime import datetime, timezone
from importlib import metadata
from pathlib import Path

from impact_envs.errors import InvalidArgumentError

RUN_JSON = "run.json"
PACKAGES = (
    "impact-robotics",
    "gymnasium",
    "mujoco",
    "numpy",
    "torch",
    "stable-baselines3",
    "pandas",
    "matplotlib",
)
"""Distributions whose versions are recorded."""


def package_versions() -> dict[str, str | None]:
    """Installed version of each of ``PACKAGES`` (``None`` if not installed)."""
    versions: dict[str, str | None] = {}
    for name in PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    if versions["impact-robotics"] is None:
        import impact_envs

        versions["impact-robotics"] = f"{impact_envs.__version__} (source tree)"
    return versions


def git_state() -> dict[str, object]:
    """``{"sha": …, "dirty": …}`` of the checkout holding this package, ``None``s outside git."""
    repo = Path(__file__).resolve().parent.parent

    def git(*args: str) -> str | None:
        try:
            out = subprocess.run(
                ["git", "-C", str(repo), *args],
                capture_output=True,
                text=True,
                timeout=10,
                check=True,
            )
        except (OSError, subprocess.SubprocessError):
            return None
        return out.stdout.strip()

    sha = git("rev-parse", "HEAD")
    status = git("status", "--porcelain", "--untracked-files=no") if sha else None
    return {"sha": sha, "dirty": None if status is None else bool(status)}


def utc_now() -> str:
    """Current UTC time, ISO 8601 to the second."""
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


def host_info() -> dict[str, object]:
    """Python, platform and CPU count (context for wall times)."""
    return {
        "python": sys.version.split()[0],
        "platform": platform.platform(),
        "cpu_count": os.cpu_count(),
    }


def read_run_json(out_dir: Path) -> dict | None:
    """The previous ``run.json`` of ``out_dir`` or ``None``; a corrupt one is bad input."""
    path = out_dir / RUN_JSON
    if not path.exists():
        return None
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise InvalidArgumentError(f"cannot read {path}: {exc}") from None


def write_run_json(out_dir: Path, data: dict) -> None:
    """Write ``run.json`` atomically (temp file + rename)."""
    path = out_dir / RUN_JSON
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=2, sort_keys=False, default=str) + "\n")
    os.replace(tmp, path)


@dataclass(frozen=True)
class RunIdentity:
    """What makes the cells of a sweep comparable; ``--resume`` must not change any of it."""

    env: str
    seed: int
    param_name: str
    controller_overrides: tuple[str, ...]
    methods: tuple[str, ...]
    values: tuple[float, ...]
    episodes: int


_EXTENDABLE = ("methods", "values")


def check_resumable(previous: dict | None, now: RunIdentity, extend: bool = False) -> None:
    """Refuse ``--resume`` into a run whose ``run.json`` arguments differ from ``now``.

    With ``extend``, methods and values may grow (every earlier method kept; new values
    appended after the earlier ones, whose positions fix the episode seeds): new cells get
    the same episode count, so no cell ends with a different count. Keys missing from an
    older ``run.json`` are not checked.
    """
    if previous is None:
        return
    args = previous.get("args", {})
    for key, value in asdict(now).items():
        if key not in args:
            continue
        was = args[key]
        now_list = list(value) if isinstance(value, tuple) else value
        growable = key in _EXTENDABLE
        if was == now_list or (growable and set(was) == set(now_list)):
            continue
        if extend and key == "methods":
            missing = [v for v in was if v not in now_list]
            if not missing:
                continue
            raise InvalidArgumentError(
                f"cannot extend: methods {missing} of the run are missing; --extend keeps "
                f"every earlier method (run.json: {was!r})")
        if extend and key == "values":
            if now_list[:len(was)] == was:
                continue
            raise InvalidArgumentError(
                f"cannot extend: the grid must start with the run's values {was!r} (an "
                "episode's seed follows its value's position); append new values after them")
        hint = "; to add methods or grid values pass --extend" if growable else ""
        raise InvalidArgumentError(
            f"cannot resume: {key} was {was!r} in run.json, now {now_list!r}; use the same "
            f"value (every cell keeps one episode count) or another --out{hint}")
