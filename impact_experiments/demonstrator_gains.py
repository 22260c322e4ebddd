"""The closed-loop demonstrator with other gains
(``python -m impact_experiments.demonstrator_gains``).

Runs the pick-and-place expert with ``compensation="closed_loop"`` and the given proportional
and integral gains under plain impedance, one env at a time, and prints per mass the successes
and the range of the TCP height minus the episode's nominal carry height while carrying (a
limit cycle shows as a wide range). This is how the
shipped gains were chosen (docs/diffusion_policy.md, "The closed-loop demonstrator"); episode
seeds are ``seed + 1000 k + round(10 m)``, so use seeds you do not report.
"""

from __future__ import annotations

import argparse
import dataclasses

import gymnasium as gym
import numpy as np

from impact_control.policy import stack_obs
from impact_envs.policies.experts import make_expert
from impact_envs.policies.scripted import CARRY, RETREAT, PickPlaceExpert


def run_episode(env: gym.Env, expert: PickPlaceExpert, seed: int) -> tuple[bool, np.ndarray]:
    """Success of one episode and the TCP height above the episode's nominal carry height [m]
at each step of its carry phase."""
    obs, _ = env.reset(seed=seed)
    expert.reset(1)
    carry_z, success = [], False
    for _ in range(env.unwrapped.task.max_episode_steps):
        obs, _, terminated, truncated, info = env.step(expert.act(stack_obs([obs]))[0])
        if expert.phase[0] == CARRY:
            carry_z.append(float(obs["ee_pos"][2] - expert.carry_z[0]))
        success = bool(info.get("is_success", False))
        if (success and expert.phase[0] == RETREAT) or terminated or truncated:
            break
    return success, np.asarray(carry_z)


def main(argv: list[str] | None = None) -> None:
    """Print successes and the carry-height error range per mass."""
    parser = argparse.ArgumentParser(prog="python -m impact_experiments.demonstrator_gains")
    parser.add_argument("--env", default="IMPACT/Hammer-v1", help="a pick-and-place env id")
    parser.add_argument("--kp", type=float, required=True, help="lift_gain [-]")
    parser.add_argument("--ki", type=float, required=True, help="lift_gain_per_s [1/s]")
    parser.add_argument("--masses", default="0.1,2,5,8", help="comma-separated [kg]")
    parser.add_argument("--episodes", type=int, default=8)
    parser.add_argument("--seed", type=int, default=90000)
    args = parser.parse_args(argv)
    base = make_expert(args.env, compensation="closed_loop")
    spec = dataclasses.replace(base.spec, lift_gain=args.kp, lift_gain_per_s=args.ki)
    for mass in (float(m) for m in args.masses.split(",")):
        env = gym.make(args.env, object_mass=mass, controller="impedance")
        wins, heights = 0, []
        for k in range(args.episodes):
            expert = PickPlaceExpert(spec, compensation="closed_loop")
            ok, carry_z = run_episode(env, expert, args.seed + 1000 * k + round(10 * mass))
            wins += ok
            heights.extend(carry_z)
        env.close()
        z = np.asarray(heights) if heights else np.full(1, np.nan)
        print(f"{args.env} k_p={args.kp:g} k_i={args.ki:g}/s m={mass:g} kg: {wins}/{args.episodes}"
              f"; TCP minus nominal carry height {100 * z.min():+.1f} to {100 * z.max():+.1f} cm",
              flush=True)


if __name__ == "__main__":
    main()
