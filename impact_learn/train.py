"""``impact-train``: train a Diffusion Policy (state-based or visuomotor) on a demonstration store.

Usage::

    impact-train --data data/hammer_vanilla.zarr --out runs/vanilla_dp --steps 30000
    impact-train --data data/hammer_vanilla.zarr --out runs/vanilla_dp --steps 30000 --resume

Outputs in ``--out``: ``policy/`` (latest EMA policy, loadable with ``DiffusionPolicy.load``),
``best/`` (EMA policy with the lowest held-out action MSE), ``train_state/`` (resumable state),
``log.csv`` and ``run.json``. ``--resume`` refuses flags that differ from the run's
(``train_resume.py``) and data other than the run's (content fingerprints).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path

import torch

from impact_control.cli import OneLineParser
from impact_control.errors import ImpactError, InvalidArgumentError, TrainingError
from impact_envs.policies.diffusion.config import DiffusionConfig
from impact_envs.policies.diffusion.model import diffusion_loss, encode, make_network
from impact_envs.policies.diffusion.normalizer import Normalizer
from impact_envs.policies.diffusion.policy import DiffusionPolicy
from impact_learn.ema import EMA
from impact_learn.train_data import TrainData, load_train_data
from impact_learn.train_log import TrainLog, evaluate
from impact_learn.train_resume import check_resume_flags
from impact_learn.train_state import (
    TrainState,
    find_train_state,
    load_train_state,
    save_train_state,
)


@dataclass(frozen=True)
class RunOptions:
    """Loop logistics of one training run (not part of the policy's hyper-parameters).

    Attributes:
        steps: Total optimizer steps (also the cosine schedule length).
        checkpoint_every: Steps between resumable checkpoints and policy exports.
        val_every: Steps between held-out evaluations (logged to log.csv).
        val_fraction: Fraction of episodes held out (at least one if there are >= 2).
        resume: Continue from ``OUT/train_state`` if present.
        progress: Show a tqdm progress bar.
    """

    steps: int
    checkpoint_every: int = 1000
    val_every: int = 1000
    val_fraction: float = 0.05
    resume: bool = False
    progress: bool = True

    def __post_init__(self) -> None:
        for flag, value in (("--steps", self.steps), ("--checkpoint-every",
                            self.checkpoint_every), ("--val-every", self.val_every)):
            if value < 1:
                raise InvalidArgumentError(f"{flag} must be >= 1, got {value}")
        if not 0.0 <= self.val_fraction < 1.0:
            raise InvalidArgumentError(f"val_fraction must be in [0, 1), got {self.val_fraction}")


def lr_at(cfg: DiffusionConfig, step: int, total_steps: int) -> float:
    """Learning rate of optimizer step ``step``: linear warm-up, then cosine decay to 0."""
    if step < cfg.lr_warmup_steps:
        return cfg.lr * step / max(1, cfg.lr_warmup_steps)
    progress = (step - cfg.lr_warmup_steps) / max(1, total_steps - cfg.lr_warmup_steps)
    return cfg.lr * 0.5 * (1.0 + math.cos(math.pi * min(progress, 1.0)))


def init_state(cfg: DiffusionConfig, obs_dim: int) -> TrainState:
    """Fresh network (seeded by ``cfg.seed``), EMA, AdamW and data generator."""
    torch.manual_seed(cfg.seed)
    net = make_network(cfg, obs_dim).train()
    ema = EMA(net, cfg.ema_power, cfg.ema_inv_gamma, cfg.ema_min, cfg.ema_max)
    optimizer = torch.optim.AdamW(
        net.parameters(), lr=cfg.lr, betas=cfg.betas, weight_decay=cfg.weight_decay
    )
    generator = torch.Generator().manual_seed(cfg.seed)
    return TrainState(net, ema, optimizer, generator)


def train_step(state: TrainState, data: TrainData, cfg: DiffusionConfig, lr: float) -> float:
    """One AdamW step on a random batch; returns the batch loss."""
    batch = data.train.sample(cfg.batch_size, state.generator)
    cond = encode(state.net, batch.obs, batch.images, state.generator)
    loss = diffusion_loss(state.net, data.scheduler, cond, batch.actions, state.generator)
    if not torch.isfinite(loss):
        raise TrainingError(
            f"non-finite loss at step {state.step + 1}; stopped before updating the weights "
            "(the exports on disk are from earlier, finite steps)")
    for group in state.optimizer.param_groups:
        group["lr"] = lr
    state.optimizer.zero_grad(set_to_none=True)
    loss.backward()
    state.optimizer.step()
    state.ema.update(state.net)
    state.step += 1
    return float(loss.detach())


def export_policy(state: TrainState, data: TrainData, cfg: DiffusionConfig, out: Path) -> None:
    """Save the EMA weights as a ``DiffusionPolicy`` checkpoint in ``out``."""
    meta = {"train_step": state.step, "dataset": data.info, **state.info}
    DiffusionPolicy(cfg, state.ema.model, data.normalizer, data.obs_dims, meta=meta).save(out)


def _start(
    cfg: DiffusionConfig, data_path: Path, out_dir: Path, opts: RunOptions
) -> tuple[DiffusionConfig, TrainData, TrainState]:
    """Load the data and a fresh or resumed state (on resume: the run's config.json, its data
    and split checked by `_check_same_run`)."""
    ckpt = find_train_state(out_dir / "train_state")
    if ckpt is not None and not opts.resume:
        raise InvalidArgumentError(f"{out_dir} holds a training run; pass --resume or pick --out")
    if ckpt is not None:
        cfg = DiffusionConfig.from_json(out_dir / "config.json")
    data = load_train_data(cfg, data_path, opts.val_fraction)
    state = init_state(cfg, data.normalizer.obs.dim)
    if ckpt is not None:
        saved = Normalizer.from_state_dict(load_train_state(state, ckpt))
        _check_same_run(state, data, saved, opts, (data_path, out_dir))
    else:
        state.info |= {"val_fraction": opts.val_fraction, "data_fingerprints": data.fingerprints}
    _note_schedule(state, opts.steps)
    out_dir.mkdir(parents=True, exist_ok=True)
    cfg.to_json(out_dir / "config.json")
    return cfg, data, state


def _check_same_run(state: TrainState, data: TrainData, saved: Normalizer, opts: RunOptions,
                    paths: tuple[Path, Path]) -> None:
    """A resumed run must read the data it started on (the content of every array it uses:
    observations, cameras, actions, episode ends) with the same held-out split."""
    data_path, out_dir = paths
    fraction = state.info.get("val_fraction", opts.val_fraction)
    if fraction != opts.val_fraction:
        raise InvalidArgumentError(
            f"--val-fraction {opts.val_fraction} differs from the run's {fraction} in "
            f"{out_dir}; leave it out or use a new --out")
    recorded = state.info.get("data_fingerprints") or {}
    changed = [name for name, value in recorded.items() if data.fingerprints.get(name) != value]
    if changed or not torch.equal(saved.obs.scale, data.normalizer.obs.scale):
        what = ", ".join(changed) or "the observation ranges"
        raise InvalidArgumentError(
            f"{data_path} is not the data the run in {out_dir} started on ({what} differ); "
            "resume on that store or use a new --out")
    if state.step > opts.steps:
        raise InvalidArgumentError(
            f"{out_dir} is at step {state.step}; valid: --steps >= {state.step}")


def _note_schedule(state: TrainState, steps: int) -> None:
    """Record in the run's info (saved with every checkpoint and export) the schedule length
    from this step on, when it changes: a run resumed with a larger ``--steps`` continues on
    the longer cosine (``lr_at``), and its exports say so (``schedule``)."""
    schedule = state.info.setdefault("schedule", [])
    if not schedule or schedule[-1]["steps"] != steps:
        schedule.append({"from_step": state.step, "steps": steps})


def train(
    cfg: DiffusionConfig, data_path: str | Path, out_dir: str | Path, opts: RunOptions
) -> TrainState:
    """Train (or resume) a policy; returns the final state. See the module docstring."""
    out_dir, data_path = Path(out_dir), Path(data_path)
    cfg, data, state = _start(cfg, data_path, out_dir, opts)
    log = TrainLog(out_dir / "log.csv", resume_step=state.step, progress=opts.progress)
    log.open_bar(total=opts.steps, initial=state.step)
    started = time.perf_counter()
    while state.step < opts.steps:
        lr = lr_at(cfg, state.step, opts.steps)
        log.add_loss(train_step(state, data, cfg, lr))
        done = state.step >= opts.steps
        if state.step % opts.val_every == 0 or done:
            metrics = evaluate(state.ema.model, data, cfg)
            log.write_row(state.step, lr, metrics, time.perf_counter() - started)
            _maybe_export_best(state, data, cfg, out_dir, metrics)
        if state.step % opts.checkpoint_every == 0 or done:
            save_train_state(state, out_dir / "train_state", data.normalizer.state_dict())
            export_policy(state, data, cfg, out_dir / "policy")
    log.close()
    run = {"steps": opts.steps, "data": str(data_path), "options": dataclasses.asdict(opts)}
    (out_dir / "run.json").write_text(json.dumps(run, indent=2) + "\n")
    return state


def _maybe_export_best(
    state: TrainState, data: TrainData, cfg: DiffusionConfig, out_dir: Path, metrics: dict
) -> None:
    score = metrics.get("val_action_mse")
    if score is None or score >= state.info.get("best_val_action_mse", math.inf):
        return
    state.info["best_val_action_mse"] = score
    state.info["best_step"] = state.step
    export_policy(state, data, cfg, out_dir / "best")


def build_parser() -> argparse.ArgumentParser:
    """Command-line interface of ``impact-train``."""
    parser = OneLineParser(prog="impact-train", description=__doc__.splitlines()[0])
    parser.add_argument("--data", required=True, help="demonstration store (DATA.zarr)")
    parser.add_argument("--out", required=True, help="output folder of the run")
    parser.add_argument("--steps", type=int, required=True, help="total optimizer steps")
    parser.add_argument("--batch-size", type=int, help="default: config's (256)")
    parser.add_argument("--seed", type=int, help="default: config's (0)")
    parser.add_argument("--resume", action="store_true", help="continue OUT/train_state")
    parser.add_argument("--config", help="DiffusionConfig JSON (overrides the defaults)")
    parser.add_argument("--checkpoint-every", type=int, default=1000, help="steps")
    parser.add_argument("--val-every", type=int, default=1000, help="steps")
    parser.add_argument("--val-fraction", type=float,
                        help=f"episodes held out (default: {RunOptions.val_fraction}; on "
                        "--resume: the run's)")
    parser.add_argument("--threads", type=int, help="torch CPU threads (default: torch's)")
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    return parser


def main(argv: list[str] | None = None) -> None:
    """Entry point of ``impact-train``; bad input exits 2 with a one-line message."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        run_from_args(args)
    except ImpactError as exc:
        parser.exit(2, f"impact-train: error: {exc}\n")


def run_from_args(args: argparse.Namespace) -> None:
    """Train as the parsed ``impact-train`` arguments say."""
    if args.threads is not None and args.threads < 1:
        raise InvalidArgumentError(f"--threads must be >= 1, got {args.threads}")
    if Path(args.out).exists() and not Path(args.out).is_dir():
        raise InvalidArgumentError(f"--out {args.out} is a file; give a directory")
    if args.threads:
        torch.set_num_threads(args.threads)
    base = DiffusionConfig.from_json(args.config) if args.config else DiffusionConfig()
    overrides = {"batch_size": args.batch_size, "seed": args.seed}
    cfg = dataclasses.replace(base, **{k: v for k, v in overrides.items() if v is not None})
    run_info = check_resume_flags(args, cfg) if args.resume else {}
    fraction = args.val_fraction
    if fraction is None:
        fraction = run_info.get("val_fraction", RunOptions.val_fraction)
    opts = RunOptions(
        steps=args.steps,
        checkpoint_every=args.checkpoint_every,
        val_every=args.val_every,
        val_fraction=fraction,
        resume=args.resume,
        progress=not args.no_progress,
    )
    state = train(cfg, args.data, args.out, opts)
    print(f"trained {state.step} steps; policy in {Path(args.out) / 'policy'}")


if __name__ == "__main__":
    main()
