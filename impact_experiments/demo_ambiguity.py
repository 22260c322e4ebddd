"""Can a state-based policy tell the mass? (``python -m impact_experiments.demo_ambiguity
DATA.zarr``)

For a demonstration store collected over a mass range, this measures how far the commanded
height of the light demos differs from that of their nearest neighbours in the policy's own
input space (every observation key, min-max normalized to [-1, 1] as the diffusion policy
normalizes it, ``n_obs_steps`` frames stacked). It looks at the lift: gripper commanded
closed and the object between ``--low`` and ``--high`` above its resting height, before the
carry has moved it sideways. If the neighbours of a light demo's states are mostly heavy demos
that command a larger overshoot, a policy that sees only these inputs is trained to command
the heavy overshoot in the light demo's state (docs/diffusion_policy.md, "The closed-loop
demonstrator").
"""

from __future__ import annotations

import argparse

import numpy as np

from impact_envs.policies.diffusion.normalizer import fit_minmax
from impact_learn.dataset import load_replay

OBS_KEYS = ("ee_pos", "ee_rot6d", "gripper_width", "object_pos", "object_rot6d", "goal_pos")


def lift_rows(data: dict[str, np.ndarray], ends: np.ndarray, low_m: float, high_m: float,
              n_obs_steps: int) -> tuple[np.ndarray, np.ndarray]:
    """(row index, episode index) of the lift states (at least ``n_obs_steps`` into an
    episode): gripper commanded closed, object ``low_m``–``high_m`` above its first height
    and within 2 cm (horizontally) of where it started."""
    rows, episodes = [], []
    start = 0
    for e, end in enumerate(ends):
        obj = data["object_pos"][start:end]
        risen = obj[:, 2] - obj[0, 2]
        moved = np.linalg.norm(obj[:, :2] - obj[0, :2], axis=1)
        closed = data["action"][start:end, 9] > 0.0
        mask = closed & (risen > low_m) & (risen < high_m) & (moved < 0.02)
        mask[: n_obs_steps - 1] = False
        idx = np.flatnonzero(mask) + start
        rows.append(idx)
        episodes.append(np.full(idx.shape, e))
        start = int(end)
    return np.concatenate(rows), np.concatenate(episodes)


def stacked_features(data: dict[str, np.ndarray], rows: np.ndarray,
                     n_obs_steps: int) -> np.ndarray:
    """Normalized observations of ``rows`` and the ``n_obs_steps - 1`` rows before each."""
    obs = np.concatenate([data[k] for k in OBS_KEYS], axis=1)
    norm = fit_minmax(obs)
    scaled = obs * norm.scale.numpy() + norm.offset.numpy()
    return np.concatenate([scaled[rows - k] for k in range(n_obs_steps)], axis=1)


def main(argv: list[str] | None = None) -> None:
    """Print, for light and heavy demos, the commanded height above the TCP in their own lift
    states and among the ``--k`` nearest lift states of other demos."""
    parser = argparse.ArgumentParser(prog="python -m impact_experiments.demo_ambiguity")
    parser.add_argument("data", help="demonstration store (*.zarr) over a mass range")
    parser.add_argument("--light-kg", type=float, default=1.0, help="'light': mass below this")
    parser.add_argument("--heavy-kg", type=float, default=5.0, help="'heavy': mass above this")
    parser.add_argument("--low", type=float, default=0.02, help="lift window start [m]")
    parser.add_argument("--high", type=float, default=0.10, help="lift window end [m]")
    parser.add_argument("--k", type=int, default=10, help="neighbours per state")
    parser.add_argument("--obs-steps", type=int, default=2, help="frames stacked (DP's To)")
    args = parser.parse_args(argv)
    replay = load_replay(args.data)
    data, mass = replay.data, np.asarray(replay.meta["episode_param"], dtype=float)
    rows, eps = lift_rows(data, replay.episode_ends, args.low, args.high, args.obs_steps)
    feats = stacked_features(data, rows, args.obs_steps)
    command_above_tcp = data["action"][rows, 2] - data["ee_pos"][rows, 2]
    print(f"{args.data}: {replay.n_episodes} demos, {len(rows)} lift states "
          f"(object {args.low * 100:.0f}-{args.high * 100:.0f} cm up), k = {args.k}")
    for name, sel in (("light", mass[eps] < args.light_kg), ("heavy", mass[eps] > args.heavy_kg)):
        own, nb_cmd, nb_mass = [], [], []
        for i in np.flatnonzero(sel):
            d = np.linalg.norm(feats - feats[i], axis=1)
            d[eps == eps[i]] = np.inf
            nb = np.argpartition(d, args.k)[: args.k]
            own.append(command_above_tcp[i])
            nb_cmd.append(np.median(command_above_tcp[nb]))
            nb_mass.append(np.median(mass[eps[nb]]))
        if not own:
            print(f"  {name}: no lift states")
            continue
        print(f"  {name} demos ({int(sel.sum())} states): command above TCP, own median "
              f"{np.median(own) * 100:.1f} cm; their neighbours' {np.median(nb_cmd) * 100:.1f} cm "
              f"(neighbours' median mass {np.median(nb_mass):.1f} kg)")


if __name__ == "__main__":
    main()
