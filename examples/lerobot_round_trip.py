"""Train a LeRobot policy on our demos, then evaluate it back with impact_eval (examples/README.md).

Runs in a virtualenv that holds lerobot and this package (docs/lerobot.md, "Round trip")::

    VENV/bin/python examples/lerobot_round_trip.py --out results/examples/lerobot_round_trip

1. ``impact-collect``: scripted Hammer demos at the nominal 0.2 kg (state observations);
2. ``impact-export-lerobot``: the store as a LeRobot v3.0 dataset;
3. LeRobot's own ``DiffusionPolicy``, trained with LeRobot's dataset, processors and optimizer
   preset for ``--steps`` steps (a small U-Net so that it trains on a CPU);
4. ``impact_eval.evaluate``: the LeRobot policy, wrapped in our two-method policy protocol,
   on ``IMPACT/Hammer-v0`` over ``--masses`` under impedance, IMPACT and IMPACT's paper preset.

Each stage is skipped when its output exists, so an interrupted run continues.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import torch

import impact_eval
from impact_learn import collect as impact_collect
from impact_learn import lerobot_export
from impact_learn.lerobot_compat import define_missing_torchvision_ops

ENV_ID = "IMPACT/Hammer-v0"
REPO_ID = "impact/hammer-round-trip"  # a name only: the dataset is read from its folder
RUNS = (("impedance", "impedance", "default"), ("impact", "impact", "default"),
        ("impact_paper", "impact", "paper"))
"""(label, controller, preset) of each evaluation: impedance, IMPACT, IMPACT's paper preset."""


class LeRobotPolicy:
    """A LeRobot policy behind our policy protocol: ``reset(n_envs)``, ``act(obs)`` on a batch.

    ``columns`` maps each LeRobot observation feature to the ``(entry, index)`` pairs of our
    observation dict it concatenates, read from the export's ``meta/info.json`` names
    (``ee_pos.0`` is ``obs["ee_pos"][:, 0]``)."""

    def __init__(self, policy, preprocessor, postprocessor,
                 columns: dict[str, list[tuple[str, int]]]) -> None:
        self.policy, self.pre, self.post = policy, preprocessor, postprocessor
        self.columns = columns

    def reset(self, n_envs: int) -> None:  # noqa: ARG002 - LeRobot's queues take any batch
        self.policy.reset()

    @torch.no_grad()
    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        batch = {name: torch.from_numpy(np.stack([obs[key][:, i] for key, i in cols], axis=1)
                                        .astype(np.float32))
                 for name, cols in self.columns.items()}
        action = self.policy.select_action(self.pre(batch))
        return self.post(action).numpy()


def feature_columns(dataset: Path) -> dict[str, list[tuple[str, int]]]:
    """Observation feature -> ``(entry, index)`` pairs, from the export's ``info.json``."""
    features = json.loads((dataset / "meta" / "info.json").read_text())["features"]
    return {name: [(n.rsplit(".", 1)[0], int(n.rsplit(".", 1)[1])) for n in f["names"]]
            for name, f in features.items()
            if name.startswith("observation.") and f["dtype"] == "float32"}


def make_lerobot_policy(dataset: Path, args: argparse.Namespace):
    """LeRobot's DiffusionPolicy for the export's features, sized for a CPU, and its
    processors normalizing with the export's ``meta/stats.json``."""
    from lerobot.configs.types import FeatureType
    from lerobot.datasets.lerobot_dataset import LeRobotDatasetMetadata
    from lerobot.datasets.utils import dataset_to_policy_features
    from lerobot.policies.diffusion.configuration_diffusion import DiffusionConfig
    from lerobot.policies.diffusion.modeling_diffusion import DiffusionPolicy
    from lerobot.policies.factory import make_pre_post_processors

    meta = LeRobotDatasetMetadata(REPO_ID, root=dataset)
    features = dataset_to_policy_features(meta.features)
    outputs = {k: f for k, f in features.items() if f.type is FeatureType.ACTION}
    inputs = {k: f for k, f in features.items() if k not in outputs}
    from lerobot.configs.types import NormalizationMode

    mapping = {"VISUAL": NormalizationMode.MEAN_STD, "STATE": NormalizationMode.MIN_MAX,
               "ACTION": NormalizationMode.MIN_MAX}
    if args.env_state_norm == "min_max":  # LeRobot's default mapping has no "ENV" entry
        mapping["ENV"] = NormalizationMode.MIN_MAX
    cfg = DiffusionConfig(input_features=inputs, output_features=outputs, device="cpu",
                          normalization_mapping=mapping,
                          n_obs_steps=2, horizon=16, n_action_steps=8,
                          down_dims=(64, 128, 256), noise_scheduler_type="DDIM",
                          num_inference_steps=10)
    pre, post = make_pre_post_processors(cfg, dataset_stats=meta.stats)
    return cfg, DiffusionPolicy(cfg), pre, post, meta.fps


def train(dataset: Path, run: Path, args: argparse.Namespace) -> None:
    """LeRobot's training step (its dataset with the policy's delta timestamps, its
    processors, its optimizer preset) for ``args.steps`` steps; saves policy and processors."""
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    torch.manual_seed(args.seed)
    cfg, policy, pre, post, fps = make_lerobot_policy(dataset, args)
    deltas = {k: [i / fps for i in cfg.observation_delta_indices] for k in cfg.input_features}
    deltas["action"] = [i / fps for i in cfg.action_delta_indices]
    data = LeRobotDataset(REPO_ID, root=dataset, delta_timestamps=deltas)
    loader = torch.utils.data.DataLoader(data, batch_size=args.batch_size, shuffle=True,
                                         drop_last=True,
                                         generator=torch.Generator().manual_seed(args.seed))
    optimizer = cfg.get_optimizer_preset().build(policy.parameters())
    policy.train()
    step = 0
    while step < args.steps:
        for batch in loader:
            loss, _ = policy.forward(pre(batch))
            loss.backward()
            optimizer.step()
            optimizer.zero_grad()
            step += 1
            if step % 50 == 0 or step == args.steps:
                print(f"lerobot DiffusionPolicy: step {step}/{args.steps}, loss {loss.item():.4f}")
            if step == args.steps:
                break
    for part in (policy, pre, post):
        part.save_pretrained(run)


def load(dataset: Path, run: Path) -> LeRobotPolicy:
    """The trained policy and its processors from ``run``, behind our protocol."""
    from lerobot.policies.diffusion.modeling_diffusion import DiffusionPolicy
    from lerobot.policies.factory import make_pre_post_processors

    policy = DiffusionPolicy.from_pretrained(run).eval()
    pre, post = make_pre_post_processors(policy.config, pretrained_path=str(run))
    return LeRobotPolicy(policy, pre, post, feature_columns(dataset))


def imitation_error(policy: LeRobotPolicy, store: Path, frames: int = 20) -> tuple[float, float]:
    """Mean TCP-position error [m] of the policy's action at ``frames`` demo frames (one per
    episode, its history fed first) against the demo's action, and of holding the current
    TCP position instead: does the policy imitate before it is rolled out?"""
    from impact_learn.dataset import load_replay

    torch.manual_seed(0)  # the diffusion noise: the same numbers on every run
    demos, rng = load_replay(store), np.random.default_rng(0)
    starts, ends = np.r_[0, demos.episode_ends[:-1]], demos.episode_ends
    policy_err, hold_err = [], []
    for e in np.linspace(0, len(ends) - 1, frames).astype(int):
        t = int(rng.integers(starts[e] + 1, ends[e]))
        policy.reset(1)
        for k in (t - 1, t):
            action = policy.act({key: v[k:k + 1] for key, v in demos.data.items()})
        target = demos.data["action"][t, :3]
        policy_err.append(np.linalg.norm(action[0, :3] - target))
        hold_err.append(np.linalg.norm(demos.data["ee_pos"][t] - target))
    return float(np.mean(policy_err)), float(np.mean(hold_err))


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
    parser.add_argument("--demos", type=int, default=100, help="scripted demos at 0.2 kg")
    parser.add_argument("--steps", type=int, default=500, help="LeRobot training steps")
    parser.add_argument("--batch-size", type=int, default=64)
    parser.add_argument("--masses", default="0.2,2.5,5", type=_masses,
                        help="kg, comma-separated")
    parser.add_argument("--episodes", type=int, default=10, help="per mass and controller")
    parser.add_argument("--seed", type=int, default=0, help="training seed")
    parser.add_argument("--env-state-norm", choices=("identity", "min_max"), default="identity",
                        help="normalization of observation.environment_state (the object's "
                             "pose): identity is LeRobot 0.4.4's default for its ENV type")
    args = parser.parse_args(argv)
    define_missing_torchvision_ops()
    out = Path(args.out)
    store, dataset, run = out / "demos.zarr", out / "lerobot_dataset", out / "lerobot_policy"
    if not store.exists():
        impact_collect.main(["--env", ENV_ID, "--out", str(store), "--episodes",
                             str(args.demos), "--mass", "0.2"])
    if not dataset.exists():
        lerobot_export.main(["--data", str(store), "--out", str(dataset)])
    if not (run / "model.safetensors").exists():
        train(dataset, run, args)
    err, hold = imitation_error(load(dataset, run), store)
    print(f"imitation: action position error on demo frames {100 * err:.1f} cm "
          f"(holding the current TCP position: {100 * hold:.1f} cm)")
    for label, controller, preset in RUNS:
        where = out / f"eval_{label}"
        table = impact_eval.evaluate(load(dataset, run), ENV_ID, args.masses, where,
                                     episodes=args.episodes, controller=controller,
                                     controller_preset=preset, name=f"lerobot_dp_{label}",
                                     envs_per_worker=args.episodes,
                                     resume=(where / "episodes.csv").exists())
        rates = table.groupby("param_value")["success"].agg(["sum", "count"])
        print(label, {m: f"{int(r['sum'])}/{int(r['count'])}" for m, r in rates.iterrows()})

if __name__ == "__main__":
    main()
