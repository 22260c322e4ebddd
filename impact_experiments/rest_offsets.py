"""The estimated external wrench of a robot at rest, without contact, at five poses: what a
robot profile's torque-sensor offsets and model errors show the estimator (issue 39).

    python -m impact_experiments.rest_offsets [--realism fr3] [--episodes 5] [--seed 0]

Each episode of ``IMPACT/Hammer-v1`` (the hammer on the table, out of reach) moves the TCP
under plain impedance to each of ``POSES_M`` (offsets from the home TCP [m, world]) over 2 s,
holds it 2 s and averages the controller's estimated external wrench over the last 0.5 s.
Prints one row per episode and pose: the force's norm [N] and components, the moment's norm
[Nm], and per episode the spread of the force between poses.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

import impact_envs  # noqa: F401 - registers the envs
from impact_control.lie import rot6d_from_matrix
from impact_envs.envs.options import REALISMS, RobotOptions

POSES_M = ((0.0, 0.0, 0.0), (0.10, 0.15, 0.0), (-0.10, -0.15, 0.05), (0.12, -0.10, -0.10),
           (0.0, 0.20, 0.10))
"""TCP offsets from the home pose [m, world]: five rest poses spread over the workspace."""
MOVE_STEPS, HOLD_STEPS, AVERAGE_STEPS = 60, 60, 15
"""Policy steps (30 Hz) of the move, the hold, and the hold's end that is averaged."""


def rest_wrenches(realism: str, episode_seed: int) -> list[np.ndarray]:
    """(6,) mean estimated wrench [N, Nm, world] at each of ``POSES_M``, one episode."""
    env = gym.make("IMPACT/Hammer-v1", controller="impedance",
                   robot=RobotOptions(realism=realism), object_mass=0.5)
    env.reset(seed=episode_seed)
    u = env.unwrapped
    home = u.dynamics.pos_ee_world.copy()
    rot6d = rot6d_from_matrix(u.dynamics.rot_ee_world)
    start, out = home.copy(), []
    for offset in POSES_M:
        goal = home + np.asarray(offset)
        samples = []
        for k in range(MOVE_STEPS + HOLD_STEPS):
            pos = start + (goal - start) * min(1.0, (k + 1) / MOVE_STEPS)
            env.step(np.concatenate([pos, rot6d, [-1.0]]))
            if k >= MOVE_STEPS + HOLD_STEPS - AVERAGE_STEPS:
                samples.append(u.controller.signals.wrench_ext_world.copy())
        out.append(np.mean(samples, axis=0))
        start = goal
    env.close()
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m impact_experiments.rest_offsets",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--realism", choices=REALISMS, default="fr3")
    parser.add_argument("--episodes", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    print("episode pose |F| [N]  Fx Fy Fz [N]  |M| [Nm]")
    for e in range(args.episodes):
        wrenches = rest_wrenches(args.realism, args.seed + e)
        for p, w in enumerate(wrenches):
            print(f"{e:7d} {p:4d} {np.linalg.norm(w[:3]):6.2f}  "
                  f"{w[0]:6.2f} {w[1]:6.2f} {w[2]:6.2f}  {np.linalg.norm(w[3:]):6.3f}")
        forces = np.array([w[:3] for w in wrenches])
        spread = np.linalg.norm(forces - forces.mean(axis=0), axis=1).max()
        print(f"        episode {e}: largest distance of a pose's force from the mean "
              f"{spread:.2f} N")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
