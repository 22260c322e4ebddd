"""Warm-robot rows of a sweep: the internal model of one unscored warm-up episode per cell.

The paper's Phase B (a load the internal model has met before) as a sweep row
(``MethodSpec.warm``, docs/eval.md "Warm robot"). Workers call ``warm_up`` once per
(method, value) cell and start every scored episode of the cell from its snapshot.
"""

from __future__ import annotations

from impact_control.policy import Policy
from impact_eval.grid import episode_seed
from impact_eval.rollout import EpisodeJob, LockstepBatch

WARMUP_EPISODE = 2**20
"""Episode index whose seed drives a cell's warm-up episode (no scored episode reaches it)."""


def warm_up(env: object, policy: Policy, param_name: str, policy_dt: float,
            base_seed: int, value_index: int, value: float) -> object:
    """Run the cell's warm-up episode on ``env`` and return its internal model's snapshot.

    The episode runs alone (a batch of one) from a fresh internal model, with the seed
    ``episode_seed(base_seed, value_index, WARMUP_EPISODE)``: every worker that runs a part of
    the cell computes the same snapshot (weights and replay buffer, ``InternalModel.snapshot``).
    """
    env.unwrapped.warm_start(None)  # type: ignore[attr-defined]
    seed = episode_seed(base_seed, value_index, WARMUP_EPISODE)
    LockstepBatch([env], policy, param_name, policy_dt).run(
        [EpisodeJob(value, seed, WARMUP_EPISODE)], lambda i, m: None)
    return env.unwrapped.controller.internal_model.snapshot()  # type: ignore[attr-defined]
