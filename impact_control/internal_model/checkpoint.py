"""The internal model's checkpoint files: weights as ``.safetensors`` beside a ``.json`` of the
same stem holding the format version, the feature layout and the model's config.

Loaded without pickle. ``safetensors`` comes with the benchmark ([bench]); a robot PC's light
install lacks it, and saving or loading there is a one-line ``CheckpointError``.
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from impact_control.errors import CheckpointError
from impact_control.internal_model.config import InternalModelConfig
from impact_control.internal_model.net import FEATURE_NAMES, FORMAT_VERSION

__all__ = ["read_config", "read_weights", "write_checkpoint"]


def write_checkpoint(path: str | Path, weights: dict[str, np.ndarray],
                     config: InternalModelConfig) -> Path:
    """Write ``weights`` to ``path`` (.safetensors) and the config to the same stem + .json."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    _safetensors().save_file(dict(weights), str(path))
    meta = {"format_version": FORMAT_VERSION, "feature_names": list(FEATURE_NAMES),
            "config": asdict(config)}
    path.with_suffix(".json").write_text(json.dumps(meta, indent=2))
    return path


def read_config(path: str | Path) -> InternalModelConfig:
    """The config saved beside the weights at ``path``.

    Raises:
        CheckpointError: A missing .json or a config this version cannot build.
    """
    meta_path = Path(path).with_suffix(".json")
    if not meta_path.is_file():
        raise CheckpointError(f"missing internal model config {meta_path}")
    saved = json.loads(meta_path.read_text()).get("config", {})
    try:
        return InternalModelConfig(**saved)
    except TypeError as exc:
        raise CheckpointError(f"invalid internal model config in {meta_path}: {exc}") from exc


def read_weights(path: str | Path, config: InternalModelConfig) -> dict[str, np.ndarray]:
    """The weights at ``path``, checked against the feature layout and ``config``'s shape.

    Raises:
        CheckpointError: Missing files, another feature layout or network shape, unreadable
            weights.
    """
    path = Path(path)
    meta_path = path.with_suffix(".json")
    if not path.is_file() or not meta_path.is_file():
        raise CheckpointError(f"missing internal model files {path} / {meta_path}")
    meta = json.loads(meta_path.read_text())
    saved = meta.get("config", {})
    same_shape = saved.get("history_length") == config.history_length and tuple(
        saved.get("hidden_sizes", ())
    ) == tuple(config.hidden_sizes)
    if meta.get("feature_names") != list(FEATURE_NAMES) or not same_shape:
        raise CheckpointError(f"internal model checkpoint {path} does not match the config")
    try:
        return _safetensors().load_file(str(path))
    except (RuntimeError, OSError, ValueError) as exc:
        raise CheckpointError(f"cannot load internal model weights {path}: {exc}") from exc


def _safetensors() -> Any:
    """``safetensors.numpy``, or a one-line ``CheckpointError`` naming how to install it."""
    try:
        import safetensors.numpy
    except ImportError:
        raise CheckpointError("saving or loading an internal model needs safetensors "
                              "(pip install safetensors, or the [bench] extra)") from None
    return safetensors.numpy
