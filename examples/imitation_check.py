"""Does a policy imitate its demos before it is rolled out? (docs/lerobot.md, issue 40)

For ``--frames`` demo frames (one per episode, spread over the store, at a random step of it),
the policy is reset, fed the frame before and the frame itself (its two observations), and
its first action is compared with the demo's: the TCP-position error [cm], against the error
of holding the current TCP position, and the gripper command's absolute error::

    python examples/imitation_check.py --data STORE --dp impact_envs/checkpoints/hammer/vanilla
    VENV/bin/python examples/imitation_check.py --data STORE \\
        --lerobot impact_envs/checkpoints/hammer/lerobot_dp      # in the LeRobot venv

Each frame's diffusion noise is seeded by its episode index (``seed_envs``), so a rerun
prints the same numbers.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass

import numpy as np

from impact_control.policy import SeededPolicy
from impact_learn.dataset import load_replay

ENV_ID = "IMPACT/Hammer-v1"


@dataclass(frozen=True)
class Imitation:
    """Means over the frames: position error of the policy's action and of holding still
    [m], gripper command's absolute error (commands in [-1, 1])."""

    position_m: float
    position_median_m: float
    hold_m: float
    gripper: float


def imitation(policy: SeededPolicy, store: str, frames: int = 40) -> Imitation:
    """The policy's first action at ``frames`` demo frames against the demo's."""
    demos, rng = load_replay(store), np.random.default_rng(0)
    starts, ends = np.r_[0, demos.episode_ends[:-1]], demos.episode_ends
    pos, hold, grip = [], [], []
    for e in np.linspace(0, len(ends) - 1, frames).astype(int):
        t = int(rng.integers(starts[e] + 1, ends[e]))
        policy.reset(1)
        policy.seed_envs([int(e)])
        for k in (t - 1, t):
            action = policy.act({key: v[k:k + 1] for key, v in demos.data.items()})
        target = demos.data["action"][t]
        pos.append(np.linalg.norm(action[0, :3] - target[:3]))
        hold.append(np.linalg.norm(demos.data["ee_pos"][t] - target[:3]))
        grip.append(abs(float(action[0, 9]) - float(target[9])))
    return Imitation(float(np.mean(pos)), float(np.median(pos)), float(np.mean(hold)),
                     float(np.mean(grip)))


def main(argv: list[str] | None = None) -> None:
    """Load the policy, print the imitation errors."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", required=True, help="an impact-collect store (*.zarr)")
    which = parser.add_mutually_exclusive_group(required=True)
    which.add_argument("--dp", help="our diffusion-policy checkpoint folder")
    which.add_argument("--lerobot", help="a LeRobot policy folder (needs lerobot)")
    parser.add_argument("--frames", type=int, default=40)
    args = parser.parse_args(argv)
    if args.dp:
        from impact_envs.policies.diffusion.policy import DiffusionPolicy

        policy = DiffusionPolicy.load(args.dp)
    else:
        from impact_lerobot.policy import load_lerobot_policy

        policy = load_lerobot_policy(args.lerobot, ENV_ID)
    out = imitation(policy, args.data, args.frames)
    print(f"imitation over {args.frames} demo frames: position error {100 * out.position_m:.2f} "
          f"cm (median {100 * out.position_median_m:.2f}), holding still "
          f"{100 * out.hold_m:.2f} cm, gripper command error {out.gripper:.3f}")


if __name__ == "__main__":
    main()
