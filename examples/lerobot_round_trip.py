"""Train a LeRobot policy on our demos, then evaluate it back with impact_eval (examples/README.md).

Runs in a virtualenv that holds lerobot and this package (docs/lerobot.md, "Round trip")::

    VENV/bin/python examples/lerobot_round_trip.py --out results/examples/lerobot_round_trip

1. ``impact-collect``: scripted Hammer demos at the nominal 0.2 kg (state observations);
2. ``impact-export-lerobot``: the store as a LeRobot v3.0 dataset;
3. LeRobot's own ``lerobot-train``: its ``DiffusionPolicy`` (a small U-Net so that it trains
   on a CPU), its dataset, processors, optimizer and schedule, for ``--steps`` steps; the
   defaults are the recipe of the shipped ``hammer/lerobot_dp`` checkpoint (docs/lerobot.md);
4. ``impact_eval.evaluate``: the LeRobot policy behind our policy protocol
   (``impact_lerobot.policy``),
   on ``IMPACT/Hammer-v1`` over ``--masses`` under impedance, IMPACT and IMPACT's paper preset.

Each stage is skipped when its output exists, so an interrupted run continues.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

from imitation_check import imitation

import impact_eval
from impact_learn import collect as impact_collect
from impact_learn import lerobot_export
from impact_learn.lerobot_compat import define_missing_torchvision_ops
from impact_lerobot.policy import LeRobotPolicy, load_lerobot_policy

ENV_ID = "IMPACT/Hammer-v1"
REPO_ID = "impact/hammer"  # a name only: the dataset is read from its folder
RUNS = (("impedance", "impedance", "default"), ("impact", "impact", "default"),
        ("impact_paper", "impact", "paper"))
"""(label, controller, preset) of each evaluation: impedance, IMPACT, IMPACT's paper preset."""


def train_command(dataset: Path, out: Path, args: argparse.Namespace) -> list[str]:
    """LeRobot's own ``lerobot-train`` on the export: its Diffusion Policy sized for a CPU
    (U-Net ``down_dims`` (32, 64, 128), horizon 16, 2 observations, 8 actions executed, DDIM
    with 10 inference steps), AdamW at ``--lr`` with its cosine schedule (500 warm-up steps),
    the environment state normalized as the state (``--env-state-norm``)."""
    mapping = {"VISUAL": "MEAN_STD", "STATE": "MIN_MAX", "ACTION": "MIN_MAX"}
    if args.env_state_norm == "min_max":  # LeRobot 0.4.4's default mapping has no "ENV" entry
        mapping["ENV"] = "MIN_MAX"
    lerobot_train = Path(sys.executable).with_name("lerobot-train")
    return [str(lerobot_train), f"--dataset.repo_id={REPO_ID}", f"--dataset.root={dataset}",
            "--policy.type=diffusion", "--policy.device=cpu", "--policy.push_to_hub=false",
            "--policy.down_dims=[32,64,128]", "--policy.n_obs_steps=2", "--policy.horizon=16",
            "--policy.n_action_steps=8", "--policy.noise_scheduler_type=DDIM",
            "--policy.num_inference_steps=10", f"--policy.optimizer_lr={args.lr}",
            f"--policy.normalization_mapping={json.dumps(mapping)}",
            f"--steps={args.steps}", f"--batch_size={args.batch_size}", "--log_freq=200",
            f"--save_freq={args.save_every}", "--eval_freq=0", "--num_workers=1",
            "--wandb.enable=false", f"--output_dir={out}", f"--seed={args.seed}"]


def train(dataset: Path, out: Path, args: argparse.Namespace) -> Path:
    """Run (or resume) ``lerobot-train``; returns its last ``pretrained_model`` folder."""
    last = out / "checkpoints" / "last" / "pretrained_model"
    if (out / "checkpoints" / f"{args.steps:06d}" / "pretrained_model").is_dir():
        return last
    if (last / "train_config.json").is_file():  # interrupted: LeRobot's own resume
        command = [str(Path(sys.executable).with_name("lerobot-train")),
                   f"--config_path={last / 'train_config.json'}", "--resume=true"]
    else:
        command = train_command(dataset, out, args)
    subprocess.run(command, check=True)
    return last


def load(run: Path) -> LeRobotPolicy:
    """The trained policy and its processors behind our protocol (``impact_lerobot.policy``)."""
    return load_lerobot_policy(run, ENV_ID)


def _masses(text: str) -> list[float]:
    """``--masses``: comma-separated numbers (kg); argparse reports anything else in one line."""
    try:
        return [float(m) for m in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"invalid masses {text!r}; valid: e.g. 0.2,2.5,5") from None


def main(argv: list[str] | None = None) -> None:
    """Collect, export, train, evaluate (see the module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results/examples/lerobot_round_trip")
    parser.add_argument("--demos", type=int, default=200, help="scripted demos at 0.2 kg")
    parser.add_argument("--steps", type=int, default=12000, help="LeRobot training steps")
    parser.add_argument("--batch-size", type=int, default=64)
    parser.add_argument("--lr", type=float, default=1e-3, help="AdamW learning rate")
    parser.add_argument("--save-every", type=int, default=2000,
                        help="checkpoint every N steps (an interrupted run resumes)")
    parser.add_argument("--masses", default="0.2,2.5,5", type=_masses,
                        help="kg, comma-separated")
    parser.add_argument("--episodes", type=int, default=10, help="per mass and controller")
    parser.add_argument("--seed", type=int, default=0, help="training seed")
    parser.add_argument("--env-state-norm", choices=("identity", "min_max"), default="min_max",
                        help="normalization of observation.environment_state (the object's "
                             "pose): identity is LeRobot 0.4.4's default for its ENV type")
    args = parser.parse_args(argv)
    define_missing_torchvision_ops()
    out = Path(args.out)
    store, dataset = out / "demos.zarr", out / "lerobot_dataset"
    if not store.exists():
        impact_collect.main(["--env", ENV_ID, "--out", str(store), "--episodes",
                             str(args.demos), "--mass", "0.2", "--seed", "0"])
    if not dataset.exists():
        lerobot_export.main(["--data", str(store), "--out", str(dataset)])
    run = train(dataset, out / "lerobot_train", args)
    check = imitation(load(run), str(store), frames=min(40, args.demos))
    print(f"imitation: action position error on demo frames {100 * check.position_m:.2f} cm "
          f"(holding the current TCP position: {100 * check.hold_m:.2f} cm), gripper command "
          f"error {check.gripper:.3f}")
    for label, controller, preset in RUNS:
        where = out / f"eval_{label}"
        table = impact_eval.evaluate(load(run), ENV_ID, args.masses, where,
                                     episodes=args.episodes, controller=controller,
                                     controller_preset=preset, name=f"round_trip_{label}",
                                     envs_per_worker=args.episodes,
                                     resume=(where / "episodes.csv").exists())
        rates = table.groupby("param_value")["success"].agg(["sum", "count"])
        print(label, {m: f"{int(r['sum'])}/{int(r['count'])}" for m, r in rates.iterrows()})


if __name__ == "__main__":
    main()
