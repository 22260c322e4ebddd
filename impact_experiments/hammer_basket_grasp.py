"""The HammerBasket expert's grasp: the authors' (home orientation, 6.9 deg off square to the
handle, fingers around the body origin) against ours, as success counts.

Run ``python -m impact_experiments.hammer_basket_grasp``. Their demonstrator under
impedance with the privileged ``m g / K`` offset, on ``IMPACT/HammerBasket-v1``: their grasp,
turned square to the handle, and turned and centred on the handle (shipped), on the same
seeds and masses; each episode runs ``--steps`` policy steps (700: the expert has
released the hammer and retreated by step ~650) and is scored by the task's own test.
Prints one line per grasp and writes nothing.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

import impact_envs  # noqa: F401 - registers the envs
from impact_control.policy import stack_obs
from impact_envs.policies.scripted_hammer_basket import hammer_basket_expert
from impact_envs.tasks.hammer_basket import (
    HANDLE_Y_AT_ORIGIN_M,
    HANDLE_YAW_RAD,
    HammerBasketTask,
)

GRASPS = {"theirs (home orientation, body origin)": (0.0, 0.0),
          "square to the handle, body origin": (HANDLE_YAW_RAD, 0.0),
          "square to the handle, its centreline (shipped)": (HANDLE_YAW_RAD,
                                                             HANDLE_Y_AT_ORIGIN_M)}
"""Label -> (grasp yaw [rad], grasp point's y [m]), hammer frame."""


def run_one(env: gym.Env, grasp: tuple[float, float], mass: float, seed: int,
            steps: int) -> bool:
    """One episode's success under the expert with ``grasp`` (yaw, y)."""
    expert = hammer_basket_expert("privileged", grasp_yaw_obj_rad=grasp[0],
                                  grasp_y_obj_m=grasp[1])
    obs, _ = env.reset(seed=seed, options={"object_mass": mass})
    expert.reset(1, object_mass_kg=np.array([mass]))
    info: dict = {}
    for _ in range(steps):
        obs, _, _, _, info = env.step(expert.act(stack_obs([obs]))[0])
    return bool(info["is_success"])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--masses", type=float, nargs="+", default=[0.2, 4.0])
    parser.add_argument("--seeds", type=int, nargs="+", default=list(range(11, 23)))
    parser.add_argument("--steps", type=int, default=700)
    args = parser.parse_args(argv)
    if args.steps < 1:
        parser.error(f"--steps {args.steps}: valid: >= 1")
    low, high = HammerBasketTask.params[0].low, HammerBasketTask.params[0].high
    if any(not low <= m <= high for m in args.masses):
        parser.error(f"--masses {args.masses}: valid: {low:g} to {high:g} kg")
    env = gym.make("IMPACT/HammerBasket-v1", controller="impedance")
    for label, grasp in GRASPS.items():
        wins = [run_one(env, grasp, m, s, args.steps) for m in args.masses for s in args.seeds]
        print(f"{label}: {sum(wins)}/{len(wins)} (masses {args.masses} kg, seeds "
              f"{args.seeds[0]}..{args.seeds[-1]}, {args.steps} steps)", flush=True)
    env.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
