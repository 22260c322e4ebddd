"""``run.json``: provenance of a sweep (versions, git SHA, CLI, env spec, periods, wall times)."""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
from dataclasses import asdict, dataclass, field
from pathlib import Path

from impact_control.errors import InvalidArgumentError
from impact_control.runinfo import host_info, utc_now  # noqa: F401 - run.json fields, re-exported
from impact_control.runinfo import package_versions as control_package_versions
from impact_eval.cli_options import declared
from impact_eval.code_check import check_fingerprints
from impact_eval.run_migration import SPEC_FORMAT, identity_of
from impact_eval.spec import SweepSpec

RUN_JSON = "run.json"
IDENTITY_JSON = "identity.json"
"""What the run's cells are (``RunIdentity``), written before its first row: ``--resume``
checks it even when run.json is gone."""
PACKAGES = (
    "impact-robotics",
    "gymnasium",
    "mujoco",
    "numpy",
    "torch",
    "stable-baselines3",
    "pandas",
    "matplotlib",
    "lerobot",
)
"""Distributions whose versions are recorded (``lerobot``: the ``lerobot_*`` methods' library,
``None`` where it is not installed)."""


def package_versions() -> dict[str, str | None]:
    """Installed version of each of ``PACKAGES`` (``None`` if not installed)."""
    return control_package_versions(PACKAGES)


NOT_CODE = ("results", "docs")
"""Folders whose uncommitted changes do not change a row (``git_state``'s ``code_diff``)."""


def git_state() -> dict[str, object]:
    """``{"sha": …, "dirty": …, "code_diff": …}`` of the checkout holding this package
    (``None``s outside git): ``dirty`` whether any tracked file differs from HEAD,
    ``code_diff`` the sha256 of ``git diff HEAD`` outside ``NOT_CODE`` (None: no change)."""
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
    diff = git("diff", "HEAD", "--", ".", *(f":(exclude){d}" for d in NOT_CODE)) if sha else None
    return {"sha": sha, "dirty": None if status is None else bool(status),
            "code_diff": hashlib.sha256(diff.encode()).hexdigest() if diff else None}


def _read_object(path: Path) -> dict | None:
    """The JSON object in ``path``, ``None`` if absent; anything else is bad input."""
    if not path.exists():
        return None
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise InvalidArgumentError(f"cannot read {path}: {' '.join(str(exc).split())}") from None
    if not isinstance(data, dict):
        raise InvalidArgumentError(f"{path} is not a JSON object; restore it or use another --out")
    return data


def read_run_json(out_dir: Path) -> dict | None:
    """The previous ``run.json`` of ``out_dir`` or ``None``; a corrupt one is bad input."""
    return _read_object(out_dir / RUN_JSON)


def recorded_identity(out_dir: Path) -> dict | None:
    """The identity a run in ``out_dir`` recorded, in the current layout
    (``run_migration.identity_of``): ``identity.json``, else run.json's, else ``None``."""
    identity = identity_of(_read_object(out_dir / IDENTITY_JSON))
    return identity if identity is not None else identity_of(read_run_json(out_dir))


def write_identity(out_dir: Path, identity: RunIdentity) -> None:
    """Write ``identity.json`` atomically (before the first row of the run)."""
    path = out_dir / IDENTITY_JSON
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(identity.to_json(), indent=2) + "\n")
    os.replace(tmp, path)


def write_run_json(out_dir: Path, data: dict) -> None:
    """Write ``run.json`` atomically (temp file + rename)."""
    path = out_dir / RUN_JSON
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=2, sort_keys=False, default=str) + "\n")
    os.replace(tmp, path)


@dataclass(frozen=True)
class RunIdentity:
    """What makes the cells of a sweep comparable; ``--resume`` must not change any of it: the
    spec, and what ``prepare`` resolved from the env and the methods."""

    spec: SweepSpec
    param_name: str
    """The swept parameter, resolved (``spec.param`` or the env's first)."""
    method_controllers: dict[str, dict[str, object]] = field(default_factory=dict)
    """Per method: env controller, preset and warm start (a name that now means another
    controller cannot resume the earlier rows)."""
    policy_fingerprints: dict[str, str | None] = field(default_factory=dict)
    """Per method: sha256 of the checkpoint it loads (``checkpoints.fingerprint``; None:
    none, e.g. a scripted expert)."""

    def to_json(self) -> dict[str, object]:
        """identity.json and run.json's ``"identity"`` (``run_migration.identity_of`` reads
        every earlier layout into this one)."""
        return {"spec_format": SPEC_FORMAT, "spec": self.spec.to_json(),
                "param_name": self.param_name, "method_controllers": self.method_controllers,
                "policy_fingerprints": self.policy_fingerprints}


def check_resumable(recorded: dict | None, now: RunIdentity, extend: bool = False,
                    has_rows: bool = False) -> None:
    """Refuse ``--resume`` into a run whose recorded identity differs from ``now``.

    ``recorded`` is ``recorded_identity(out)``. Each spec field is compared as its declaration
    says (``cli_options.option``'s ``resume``); with ``extend``, methods and values may grow
    (every earlier method kept; new values appended after the earlier ones, whose positions
    fix the episode seeds): new cells get the same episode count, so no cell ends with a
    different count. Rows without any recorded identity are refused (``has_rows``).
    """
    if recorded is None:
        if has_rows:
            raise InvalidArgumentError(
                "cannot resume: the output has episodes but neither identity.json nor a "
                "run.json with its arguments, so what they were run with cannot be checked; "
                "restore run.json or use another --out")
        return
    _check_controllers(recorded.get("method_controllers"), now.method_controllers)
    check_fingerprints(recorded.get("policy_fingerprints"), now.policy_fingerprints)
    was_spec = recorded.get("spec") or {}
    for f, opt in declared(SweepSpec):
        if opt.resume != "free":
            was = was_spec.get(f.name, _listed(f.default))
            _check_same(f.name, was, _listed(getattr(now.spec, f.name)),
                        opt.resume == "grow", extend)
    if "param_name" in recorded:
        _check_same("param_name", recorded["param_name"], now.param_name, False, extend)


def _listed(value: object) -> object:
    return list(value) if isinstance(value, tuple) else value


def _check_same(key: str, was: object, now: object, growable: bool, extend: bool) -> None:
    """One recorded value against the new one (``check_resumable``)."""
    if was == now or (growable and set(was) == set(now)):  # type: ignore[arg-type]
        return
    if extend and key == "methods":
        missing = [v for v in was if v not in now]  # type: ignore[attr-defined]
        if not missing:
            return
        raise InvalidArgumentError(
            f"cannot extend: methods {missing} of the run are missing; --extend keeps "
            f"every earlier method (run.json: {was!r})")
    if extend and growable:
        if now[:len(was)] == was:  # type: ignore[index, arg-type]
            return
        raise InvalidArgumentError(
            f"cannot extend: the grid must start with the run's values {was!r} (an "
            "episode's seed follows its value's position); append new values after them")
    hint = "; to add methods or grid values pass --extend" if growable else ""
    raise InvalidArgumentError(
        f"cannot resume: {key} was {was!r} in run.json, now {now!r}; use the same "
        f"value (every cell keeps one episode count) or another --out{hint}")


def _with_later_robot_fields(setting: object) -> object:
    """A recorded method setting whose ``robot`` lacks fields added to ``RobotOptions`` since
    (issue 39's realism fields), completed with their defaults: a default reproduces the
    behaviour from before the field existed (``realism="ideal"`` bit for bit), so a run
    started before then resumes."""
    if not isinstance(setting, dict) or not isinstance(setting.get("robot"), dict):
        return setting
    from impact_envs.envs.options import RobotOptions

    before = {**asdict(RobotOptions()), "realism": "ideal"}  # the only robot before realism
    return {**setting, "robot": {**before, **setting["robot"]}}


def _check_controllers(was: object, now: dict[str, dict[str, object]]) -> None:
    """Each method present in both must run the same controller, preset and warm start."""
    if not isinstance(was, dict):
        return
    for method, setting in now.items():
        before = _with_later_robot_fields(was.get(method))
        if before is not None and before != setting:
            raise InvalidArgumentError(
                f"cannot resume: method {method!r} ran with {before} and would now run with "
                f"{setting}; use the same controller or another --out")
