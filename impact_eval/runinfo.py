"""``run.json``: provenance of a sweep (versions, git SHA, CLI, env spec, periods, wall times)."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
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


def check_resumable(
    previous: dict | None,
    env_id: str,
    seed: int,
    param_name: str,
    controller_overrides: tuple[str, ...] = (),
) -> None:
    """Refuse ``--resume`` into a run made with a different env, seed, parameter or
    controller overrides."""
    if previous is None:
        return
    args = previous.get("args", {})
    overrides = list(controller_overrides)
    checks = (("env", env_id), ("seed", seed), ("param_name", param_name),
              ("controller_overrides", overrides))
    for key, now in checks:
        if key in args and args[key] != now:
            raise InvalidArgumentError(
                f"cannot resume: {key} was {args[key]!r} in run.json, now {now!r}; "
                "use the same value or another --out"
            )
