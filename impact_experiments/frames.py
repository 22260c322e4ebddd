"""Frame strips of every task for docs/gallery.md: the scripted expert's episode under IMPACT,
four frames each (start, grasp or contact, mid-task, end), from the ``overview`` camera.

    MUJOCO_GL=egl python -m impact_experiments.frames --out docs/img [--env IMPACT/HammerBasket-v1]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import gymnasium as gym
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import impact_envs  # noqa: E402
from impact_control.policy import stack_obs  # noqa: E402
from impact_envs.envs.options import RenderOptions  # noqa: E402
from impact_envs.policies.experts import make_expert  # noqa: E402

FRACTIONS = (0.0, 0.3, 0.6, 1.0)
"""Where in the episode the four frames are taken."""


def episode_frames(env_id: str, seed: int = 0) -> list[np.ndarray]:
    """The expert's episode under IMPACT (until success or the step limit), rendered."""
    env = gym.make(env_id, controller="impact", terminate_on_success=True,
                   render_mode="rgb_array", render=RenderOptions(width=400, height=300))
    expert = make_expert(env_id)
    obs, _ = env.reset(seed=seed)
    expert.reset(1)
    frames = [env.render()]
    for _ in range(env.spec.max_episode_steps):
        obs, _, terminated, truncated, _ = env.step(expert.act(stack_obs([obs]))[0])
        frames.append(env.render())
        if terminated or truncated:
            break
    env.close()
    return frames


def save_strip(env_id: str, out: Path) -> Path:
    """One PNG of four frames of ``env_id``'s expert episode."""
    frames = episode_frames(env_id)
    picks = [frames[round(f * (len(frames) - 1))] for f in FRACTIONS]
    fig, axes = plt.subplots(1, len(picks), figsize=(3.2 * len(picks), 2.5))
    for ax, frame, f in zip(axes, picks, FRACTIONS, strict=True):
        ax.imshow(frame)
        ax.set_title(f"step {round(f * (len(frames) - 1))}", fontsize=8)
        ax.axis("off")
    fig.suptitle(env_id, fontsize=10)
    fig.tight_layout()
    path = out / f"{env_id.split('/')[-1].split('-')[0].lower()}_strip.png"
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("docs/img"))
    parser.add_argument("--env", action="append", choices=impact_envs.REGISTERED_IDS, default=None,
                        help="only this env (repeatable; default: the -v1 ids docs/gallery.md was "
                        "recorded on)")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    recorded = tuple(i for i in impact_envs.REGISTERED_IDS if i.endswith("-v1"))
    for env_id in args.env or recorded:
        print(save_strip(env_id, args.out))


if __name__ == "__main__":
    main()
