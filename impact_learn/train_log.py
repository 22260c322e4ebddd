"""Held-out evaluation and the training log (``log.csv`` + tqdm bar)."""

from __future__ import annotations

import csv
from pathlib import Path

import torch
from tqdm import tqdm

from impact_envs.policies.diffusion.config import DiffusionConfig
from impact_envs.policies.diffusion.model import (
    DiffusionNet,
    denoise,
    diffusion_loss,
    encode,
    make_inference_scheduler,
)
from impact_learn.train_data import TrainData

LOG_COLUMNS = ("step", "lr", "train_loss", "val_loss", "val_action_mse", "elapsed_s")
"""log.csv columns: optimizer step, learning rate, mean training loss since the previous row,
held-out denoising loss, held-out MSE of the Ta executed actions sampled with DDIM (normalized
action space), seconds since this process started."""
VAL_SEED = 1234


@torch.no_grad()
def evaluate(
    net: DiffusionNet, data: TrainData, cfg: DiffusionConfig, max_windows: int = 256
) -> dict[str, float]:
    """Held-out denoising loss and DDIM action MSE on a fixed subset of held-out windows.

    Uses its own generator, so evaluation does not change the training random stream.
    """
    if data.val is None or len(data.val) == 0:
        return {}
    n = min(max_windows, len(data.val))
    batch = data.val.get(torch.linspace(0, len(data.val) - 1, n).long())
    actions = batch.actions
    generator = torch.Generator().manual_seed(VAL_SEED)
    obs = encode(net, batch.obs, batch.images)  # the EMA copy is in eval mode: centre crops
    val_loss = diffusion_loss(net, data.scheduler, obs, actions, generator)
    noise = torch.randn(actions.shape, generator=generator)
    sample = denoise(net, make_inference_scheduler(cfg), obs, noise)
    start = cfg.n_obs_steps - 1
    executed = slice(start, start + cfg.n_action_steps)
    mse = torch.mean((sample[:, executed] - actions[:, executed]) ** 2)
    return {"val_loss": float(val_loss), "val_action_mse": float(mse)}


class TrainLog:
    """Appends rows to ``log.csv`` and drives the progress bar.

    Args:
        path: CSV path. Rows after ``resume_step`` (written after the last checkpoint of an
            interrupted run) are dropped; with ``resume_step == 0`` the file is restarted.
        resume_step: Step the run starts from.
        progress: Show a tqdm bar.
    """

    def __init__(self, path: Path, resume_step: int, progress: bool) -> None:
        self.path = path
        self.progress = progress
        rows = self._read_rows() if resume_step > 0 else []
        rows = [r for r in rows if int(r["step"]) <= resume_step]
        with path.open("w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=LOG_COLUMNS)
            writer.writeheader()
            writer.writerows(rows)
        self._losses: list[float] = []
        self.bar: tqdm | None = None

    def _read_rows(self) -> list[dict[str, str]]:
        if not self.path.is_file():
            return []
        with self.path.open(newline="") as f:
            return list(csv.DictReader(f))

    def open_bar(self, total: int, initial: int) -> None:
        """Start the progress bar at ``initial`` of ``total`` steps."""
        self.bar = tqdm(total=total, initial=initial, disable=not self.progress, unit="step")

    def add_loss(self, loss: float) -> None:
        """Record one training loss and advance the bar."""
        self._losses.append(loss)
        if self.bar is not None:
            self.bar.update(1)
            if len(self._losses) % 10 == 0:
                self.bar.set_postfix(loss=f"{loss:.4f}")

    def write_row(self, step: int, lr: float, metrics: dict[str, float], elapsed: float) -> None:
        """Append one CSV row (mean train loss since the previous row) and flush."""
        train_loss = sum(self._losses) / max(1, len(self._losses))
        self._losses.clear()
        row = {"step": step, "lr": f"{lr:.6g}", "train_loss": f"{train_loss:.6g}"}
        row |= {k: f"{v:.6g}" for k, v in metrics.items()}
        row["elapsed_s"] = f"{elapsed:.1f}"
        with self.path.open("a", newline="") as f:
            csv.DictWriter(f, fieldnames=LOG_COLUMNS).writerow(row)
        if self.bar is not None and self.progress and metrics:
            self.bar.write(f"step {step}: " + ", ".join(f"{k}={v}" for k, v in row.items()))

    def close(self) -> None:
        """Close the progress bar."""
        if self.bar is not None:
            self.bar.close()
