"""Where a method's policy checkpoint lives: ``$IMPACT_CHECKPOINTS`` or the shipped
``impact_envs/checkpoints``, then ``<env short name>/<variant>``."""

from __future__ import annotations

import hashlib
import json
import os
import re
from pathlib import Path

from impact_control.errors import CheckpointError
from impact_envs.envs.options import ObservationOptions

CHECKPOINTS_ENV_VAR = "IMPACT_CHECKPOINTS"
"""Environment variable overriding the shipped checkpoint root ``impact_envs/checkpoints``."""


def env_short_name(env_id: str) -> str:
    """``"IMPACT/Hammer-v1"`` (or ``"mod:IMPACT/Hammer-v1"``) -> ``"hammer"``."""
    name = env_id.rsplit(":", 1)[-1].rsplit("/", 1)[-1]
    return re.sub(r"-v\d+$", "", name).lower()


def checkpoint_dir(env_id: str, variant: str) -> Path:
    """Directory of the ``variant`` checkpoint (``vanilla``, ``augmented``, ...) of an env.

    The root is ``$IMPACT_CHECKPOINTS`` if set, else ``impact_envs/checkpoints``.

    Raises:
        CheckpointError: the directory does not exist (one-line message).
    """
    root = os.environ.get(CHECKPOINTS_ENV_VAR)
    if root is None:
        import impact_envs

        root = str(Path(impact_envs.__file__).parent / "checkpoints")
    path = Path(root) / env_short_name(env_id) / variant
    if not path.is_dir():
        raise CheckpointError(
            f"no {variant} checkpoint for {env_id}: {path} does not exist "
            f"(train one with impact-train or set ${CHECKPOINTS_ENV_VAR})"
        )
    return path


FINGERPRINT_SKIPS = ("meta.json",)
"""Checkpoint files a fingerprint leaves out: ``impact-eval`` stamps its evaluation into
``meta.json`` (``stamp.py``), which changes no action."""


def fingerprint(path: Path) -> str:
    """sha256 over a checkpoint directory's files (relative name and bytes, in name order),
    ``FINGERPRINT_SKIPS`` left out."""
    digest = hashlib.sha256()
    for file in sorted(p for p in path.rglob("*") if p.is_file()):
        if file.name in FINGERPRINT_SKIPS:
            continue
        digest.update(file.relative_to(path).as_posix().encode() + b"\0")
        digest.update(file.read_bytes())
    return digest.hexdigest()


def policy_checkpoint(env_id: str, policy: str | None) -> Path | None:
    """The checkpoint directory a policy component (``method_parts.POLICY_FORMS``) loads;
    None for one without a checkpoint (a scripted expert, a plugin's factory)."""
    if policy is None or "." not in policy or policy.startswith("scripted"):
        return None
    kind, _, variant = policy.partition(".")
    if kind == "dp" and variant == "nominal":
        try:
            return checkpoint_dir(env_id, "impact")
        except CheckpointError:
            variant = "vanilla"
    return checkpoint_dir(env_id, variant)


def checkpoint_observation(path: Path) -> ObservationOptions | None:
    """What the diffusion-policy checkpoint at ``path`` observes: the image observation its
    demonstrations were recorded with (``meta.json``, ``dataset.attrs.observation``, written by
    ``impact-collect --obs-mode``), None for a state checkpoint. The checkpoint is the one
    declaration of its cameras and image size, so a visuomotor method runs with those of its
    env's checkpoint (HammerBasket's ``basket_front``/``basket_side`` at 128², Hammer's
    ``overview``/``wrist`` at 96²).

    A checkpoint without ``meta.json`` records nothing: None here, and loading it reports
    what is wrong with it (``method_parts._dp_factory``).

    Raises:
        CheckpointError: ``meta.json`` is unreadable, or its observation invalid.
    """
    if not (path / "meta.json").is_file():
        return None
    try:
        meta = json.loads((path / "meta.json").read_text())
        recorded = meta.get("dataset", {}).get("attrs", {}).get("observation")
        if recorded is None:
            return None
        options = ObservationOptions(**recorded)
    except (OSError, ValueError, TypeError, AttributeError) as exc:
        msg = " ".join(str(exc).split())[:160]
        raise CheckpointError(
            f"cannot read the observation of checkpoint {path}: {type(exc).__name__}: {msg}"
        ) from None
    return options if options.uses_images else None


def checkpoint_demo_preset(path: Path) -> str | None:
    """The controller preset the demonstrations of the checkpoint at ``path`` were recorded
    under (``meta.json``, ``dataset.attrs.controller_preset``, written by ``impact-collect``),
    None where it records none.

    Raises:
        CheckpointError: ``meta.json`` is unreadable.
    """
    if not (path / "meta.json").is_file():
        return None
    try:
        meta = json.loads((path / "meta.json").read_text())
        preset = meta.get("dataset", {}).get("attrs", {}).get("controller_preset")
    except (OSError, ValueError, AttributeError) as exc:
        msg = " ".join(str(exc).split())[:160]
        raise CheckpointError(
            f"cannot read the demos' preset of checkpoint {path}: {type(exc).__name__}: {msg}"
        ) from None
    return preset if isinstance(preset, str) else None
