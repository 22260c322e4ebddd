"""Evaluate your own policy over object masses, like impact-eval does (examples/README.md).

    python examples/custom_policy.py --out results/examples/custom_policy
"""

import argparse

import numpy as np

import impact_eval
from impact_envs.policies.experts import make_expert


class CarefulExpert:
    """Your policy: any object with reset(n_envs) and act(batched obs) -> (B, 10) actions.
    Here: the scripted Hammer expert, with its TCP target moves capped at 1 cm per step."""

    def __init__(self) -> None:
        self.expert, self.last = make_expert("IMPACT/Hammer-v1"), None

    def reset(self, n_envs: int) -> None:
        self.expert.reset(n_envs)
        self.last = None

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        action = self.expert.act(obs)
        if self.last is not None:
            step = action[:, :3] - self.last[:, :3]
            action[:, :3] = self.last[:, :3] + np.clip(step, -0.01, 0.01)
        self.last = action.copy()
        return action


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results/examples/custom_policy")
    parser.add_argument("--episodes", type=int, default=10)
    args = parser.parse_args()
    for controller in ("impedance", "impact"):
        table = impact_eval.evaluate(CarefulExpert(), "IMPACT/Hammer-v1", [0.5, 2.0, 5.0],
                                     f"{args.out}/{controller}", episodes=args.episodes,
                                     controller=controller, name=f"careful_{controller}")
        print(controller, table.groupby("param_value")["success"].mean().to_dict())
