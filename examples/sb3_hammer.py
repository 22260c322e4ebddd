"""The paper's experiment with reinforcement learning: SB3 SAC trained on IMPACT/Hammer-v1 at
the nominal mass (dense reward, delta actions), then evaluated across masses under impedance
and under IMPACT with impact-eval (examples/README.md gives the numbers).

    OMP_NUM_THREADS=1 python examples/sb3_hammer.py --steps 30000 --out results/examples/sb3
"""

import argparse
import time
from pathlib import Path

import gymnasium as gym
import stable_baselines3 as sb3
import torch

import impact_envs  # noqa: F401  (registers the envs)
from impact_envs.wrappers import RLActions
from impact_eval.cli import main as impact_eval

if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=30000, help="SAC environment steps")
    parser.add_argument("--out", default="results/examples/sb3")
    parser.add_argument("--episodes", type=int, default=10, help="per mass and controller")
    args = parser.parse_args()
    torch.set_num_threads(1)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    env = RLActions(gym.make("IMPACT/Hammer-v1", object_mass=0.2, reward_type="dense"),
                    mode="delta")
    model = sb3.SAC("MultiInputPolicy", env, seed=0, device="cpu", verbose=0)
    t0 = time.perf_counter()
    model.learn(args.steps)
    print(f"trained {args.steps} steps in {time.perf_counter() - t0:.0f} s")
    model.save(out / "sac_hammer_delta.zip")
    zip_path = out / "sac_hammer_delta.zip"
    raise SystemExit(impact_eval([
        "--env", "IMPACT/Hammer-v1", "--method", f"sb3_impedance:{zip_path},sb3:{zip_path}",
        "--masses", "0.2,1,2,5", "--episodes", str(args.episodes), "--trust-sb3",
        "--out", str(out / "eval")]))
