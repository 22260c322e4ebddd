"""Resumable training state: weights, EMA, AdamW moments, RNG and step, without pickle.

On disk (``OUT/train_state/``)::

    tensors.safetensors   model.*, ema.*, optim.<param index>.<moment>, rng.torch
    state.json            step, EMA update count, optimizer hyper-parameters, run info

A checkpoint is written to a temporary folder and renamed into place, so an interrupted write
leaves the previous checkpoint intact.
"""

from __future__ import annotations

import json
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import torch
from safetensors.torch import load_file, save_file

from impact_control.errors import CheckpointError
from impact_envs.policies.diffusion.model import DiffusionNet
from impact_learn.ema import EMA

TENSORS_FILE = "tensors.safetensors"
STATE_FILE = "state.json"


@dataclass
class TrainState:
    """Everything that changes while training.

    Attributes:
        net: Trained network (U-Net, or camera encoder + U-Net).
        ema: EMA of ``net`` (the weights that are evaluated and shipped).
        optimizer: AdamW over ``net``'s parameters.
        generator: Source of batch indices, diffusion steps and noise.
        step: Optimizer steps done.
        info: JSON-serialisable run information (best validation score, ...).
    """

    net: DiffusionNet
    ema: EMA
    optimizer: torch.optim.Optimizer
    generator: torch.Generator
    step: int = 0
    info: dict[str, Any] = field(default_factory=dict)


def save_train_state(state: TrainState, directory: Path, extra: dict[str, torch.Tensor]) -> None:
    """Write ``state`` (plus ``extra`` tensors, e.g. the normalizer) to ``directory``."""
    tensors = {f"model.{k}": v for k, v in state.net.state_dict().items()}
    tensors |= {f"ema.{k}": v for k, v in state.ema.model.state_dict().items()}
    tensors |= {f"extra.{k}": v for k, v in extra.items()}
    tensors["rng.torch"] = state.generator.get_state()
    optim = state.optimizer.state_dict()
    for index, moments in optim["state"].items():
        for name, value in moments.items():
            if not isinstance(value, torch.Tensor):
                value = torch.tensor(value)
            tensors[f"optim.{index}.{name}"] = value
    meta = {
        "step": state.step,
        "ema_updates": state.ema.n_updates,
        "param_groups": optim["param_groups"],
        "info": state.info,
    }
    tmp, old = (
        directory.with_name(directory.name + ".tmp"),
        directory.with_name(directory.name + ".old"),
    )
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    save_file(
        {k: v.detach().cpu().contiguous() for k, v in tensors.items()}, str(tmp / TENSORS_FILE)
    )
    (tmp / STATE_FILE).write_text(json.dumps(meta, indent=2) + "\n")
    if directory.exists():
        shutil.rmtree(old, ignore_errors=True)
        directory.rename(old)
    tmp.rename(directory)
    shutil.rmtree(old, ignore_errors=True)


def find_train_state(directory: Path) -> Path | None:
    """Return the checkpoint folder to resume from (falls back to ``.old``), or None."""
    for candidate in (directory, directory.with_name(directory.name + ".old")):
        if (candidate / STATE_FILE).is_file() and (candidate / TENSORS_FILE).is_file():
            return candidate
    return None


def load_train_state(state: TrainState, directory: Path) -> dict[str, torch.Tensor]:
    """Restore ``state`` in place from ``directory``; returns the ``extra`` tensors."""
    try:
        tensors = load_file(str(directory / TENSORS_FILE))
        meta = json.loads((directory / STATE_FILE).read_text())
        state.net.load_state_dict(_strip(tensors, "model."), strict=True)
        state.ema.model.load_state_dict(_strip(tensors, "ema."), strict=True)
        state.optimizer.load_state_dict(_optimizer_dict(tensors, meta["param_groups"]))
        state.generator.set_state(tensors["rng.torch"])
        state.ema.n_updates = int(meta["ema_updates"])
        state.step = int(meta["step"])
        state.info = dict(meta["info"])
    except Exception as exc:  # corrupt files raise many types; report one line
        summary = (str(exc).splitlines() or [""])[0]
        raise CheckpointError(
            f"cannot resume from {directory}: {type(exc).__name__}: {summary}"
        ) from None
    return _strip(tensors, "extra.")


def _strip(tensors: dict[str, torch.Tensor], prefix: str) -> dict[str, torch.Tensor]:
    return {k[len(prefix) :]: v for k, v in tensors.items() if k.startswith(prefix)}


def _optimizer_dict(
    tensors: dict[str, torch.Tensor], param_groups: list[dict[str, Any]]
) -> dict[str, Any]:
    state: dict[int, dict[str, torch.Tensor]] = {}
    for key, value in _strip(tensors, "optim.").items():
        index, name = key.split(".", 1)
        state.setdefault(int(index), {})[name] = value
    groups = [{**g, "betas": tuple(g["betas"])} if "betas" in g else g for g in param_groups]
    return {"state": state, "param_groups": groups}
