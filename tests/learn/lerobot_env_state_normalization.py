"""Does LeRobot's DiffusionPolicy normalize ``observation.environment_state`` by default?

Run in the LeRobot virtualenv (docs/lerobot.md)::

    HF_HUB_OFFLINE=1 VENV/bin/python tests/learn/lerobot_env_state_normalization.py

It builds DiffusionConfig's pre-processor with made-up statistics and prints each feature
before and after it. With lerobot 0.4.4 the state and the action map their range onto [-1, 1].
The environment state, typed ``FeatureType.ENV``, comes out unchanged: the default
``normalization_mapping`` has no ``"ENV"`` entry, so it is treated as identity. Our export puts
the object's pose there (docs/lerobot.md, "Round trip").
"""

from __future__ import annotations

import torch
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.policies.diffusion.configuration_diffusion import DiffusionConfig
from lerobot.policies.factory import make_pre_post_processors


def _stats(low: float, high: float, size: int) -> dict[str, torch.Tensor]:
    lo, hi = torch.full((size,), low), torch.full((size,), high)
    return {"min": lo, "max": hi, "mean": (lo + hi) / 2, "std": (hi - lo) / 4}


def main() -> None:
    inputs = {"observation.state": PolicyFeature(type=FeatureType.STATE, shape=(4,)),
              "observation.environment_state": PolicyFeature(type=FeatureType.ENV, shape=(3,))}
    outputs = {"action": PolicyFeature(type=FeatureType.ACTION, shape=(2,))}
    stats = {"observation.state": _stats(0.0, 2.0, 4),
             "observation.environment_state": _stats(0.5, 0.6, 3), "action": _stats(0.0, 1.0, 2)}
    cfg = DiffusionConfig(input_features=inputs, output_features=outputs, device="cpu")
    pre, _ = make_pre_post_processors(cfg, dataset_stats=stats)
    batch = {"observation.state": torch.full((1, 4), 2.0),
             "observation.environment_state": torch.full((1, 3), 0.6),
             "action": torch.full((1, 2), 1.0)}
    out = pre(batch)
    print("normalization_mapping:", {k: v.value for k, v in cfg.normalization_mapping.items()})
    for key, value in batch.items():
        print(f"{key}: {value[0, 0].item():.3f} at the top of its range -> "
              f"{out[key][0, 0].item():.3f}")


if __name__ == "__main__":
    main()
