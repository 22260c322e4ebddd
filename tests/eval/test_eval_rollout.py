"""LockstepBatch: finished episodes are reported once and their policy rows are released."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
from fixtures.eval_fake import BARE_ID, FakePolicy

from impact_eval.rollout import EpisodeJob, LockstepBatch


class ReleasingPolicy(FakePolicy):
    """FakePolicy that records ``finish_envs`` calls and the step at which they came."""

    def __init__(self, push: float) -> None:
        super().__init__(push)
        self.steps = 0
        self.finished: list[tuple[int, int]] = []

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        self.steps += 1
        return super().act(obs)

    def finish_envs(self, indices: list[int]) -> None:
        self.finished.extend((int(i), self.steps) for i in indices)


def test_each_finished_env_is_released_once_when_it_ends() -> None:
    envs = [gym.make(BARE_ID, controller="impedance") for _ in range(3)]
    policy = ReleasingPolicy(0.9)
    rows: dict[int, dict[str, object]] = {}
    jobs = [EpisodeJob(m, 10 + i, i) for i, m in enumerate((0.5, 8.0, 0.5))]
    LockstepBatch(envs, policy, "object_mass", 1 / 30).run(
        jobs, lambda i, row: rows.__setitem__(i, row)
    )
    assert sorted(rows) == [0, 1, 2]
    released = dict(policy.finished)
    assert sorted(released) == [0, 1, 2] and len(policy.finished) == 3
    for i, row in rows.items():
        assert released[i] == row["length"]  # released right after its last step
    assert policy.steps == max(int(row["length"]) for row in rows.values())
