"""Lockstep rollout of a small batch of episodes with one batched ``policy.act`` per step.

Runs inside sweep workers, so it imports only NumPy, Gymnasium-free helpers and the error types.
"""

from __future__ import annotations

import random
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from impact_control.errors import SimulationError
from impact_control.policy import FinishingPolicy, Policy, SeededPolicy, stack_obs
from impact_envs.tasks.bins import MASS_PARAM, mass_info_key
from impact_eval.metrics import EpisodeTracker


@dataclass(frozen=True)
class EpisodeJob:
    """One episode to run: parameter value, paired seed and episode index."""

    value: float
    seed: int
    episode: int
    reset_value: float | None = None
    """What the env's reset gets for the parameter; None: ``value`` (a mass bin's episode:
    its drawn mass, ``value`` being the bin's lower edge; ``bins.draw_in_bin``)."""


SETTLE_S = 2.0
"""``--end-early``: an episode ends once its env has reported a settled outcome
(``ImpactEnv.outcome_settled``) on every step of this long [s]."""
SETTLED_REASON = "outcome settled"
"""The failure reason of a failed episode ended early (a successful one has none)."""

FinishCallback = Callable[[int, dict[str, object]], None]
"""Called as ``on_finish(batch_index, metric_columns)`` the moment an episode ends."""


def seed_global_rngs(seed: int) -> None:
    """Seed Python, NumPy-global and (if loaded) torch RNGs for policies that use them."""
    random.seed(seed)
    np.random.seed(seed % 2**32)
    torch = sys.modules.get("torch")
    if torch is not None:
        torch.manual_seed(seed)


def obs_is_finite(obs: object) -> bool:
    """True when every floating-point array of a (Dict) observation is finite."""
    values = obs.values() if isinstance(obs, dict) else [obs]
    for value in values:
        arr = np.asarray(value)
        if np.issubdtype(arr.dtype, np.floating) and not np.all(np.isfinite(arr)):
            return False
    return True


def _placeholder_obs(env: object) -> dict[str, np.ndarray]:
    """All-zero observation of ``env``'s Dict space (stands in for an env whose reset failed)."""
    spaces = env.observation_space.spaces  # type: ignore[attr-defined]
    return {k: np.zeros(s.shape, dtype=s.dtype) for k, s in spaces.items()}


def frames_unread(policy: object, n: int) -> np.ndarray:
    """``(n,)`` bool: the envs whose next observation's images ``policy`` will not read
    (``FrameReadingPolicy``; none for a policy without the hook)."""
    reads = getattr(policy, "frames_read_next", None)
    if reads is None:
        return np.zeros(n, dtype=bool)
    return ~np.asarray(reads(), dtype=bool)


def skip_images(env: object) -> None:
    """Tell ``env`` (an ``ImpactEnv`` under any wrappers) not to render its next images."""
    skip = getattr(getattr(env, "unwrapped", env), "skip_next_images", None)
    if skip is not None:
        skip()


def _crash_reason(exc: BaseException) -> str:
    """Failure reason of an exception raised inside an episode."""
    if isinstance(exc, SimulationError):
        return f"unstable: {exc}"
    return f"exception: {type(exc).__name__}"


class LockstepBatch:
    """Runs ``len(jobs)`` episodes on ``envs`` in lockstep; finished envs stop being stepped.

    Finished envs keep their last observation in the batch so that a stateful policy's rows stay
    aligned; their actions are discarded, and a policy with ``finish_envs(indices)`` is told so
    (the diffusion policy then samples chunks only for the envs still running).
    """

    def __init__(self, envs: Sequence[object], policy: Policy, param_name: str, policy_dt: float,
                 videos: dict[int, object] | None = None):
        self.envs = envs
        self.policy = policy
        self.param_name = param_name
        self.policy_dt = policy_dt
        self.videos = videos or {}
        """Batch index -> ``video.EpisodeVideo`` of the episodes recorded (``--video``)."""
        self.mass_key = mass_info_key(envs[0]) if envs else MASS_PARAM
        """The ``info`` key of the env's mass (``episodes.csv``'s ``drawn_mass_kg``)."""
        self.end_early = False
        """End an episode once its outcome has been settled for ``SETTLE_S`` (``--end-early``,
        ``SweepSpec.end_early``)."""
        self._settled_steps: list[int] = []
        self.with_press_diagnostics = False
        """Add ``safety.FF_PRESS_COLUMNS`` and ``NET_CONTACT_COLUMNS`` to each finished
        episode's columns (issue 54's
        diagnostic, ``impact_experiments.ff_press``; never in ``episodes.csv``)."""

    def run(
        self,
        jobs: Sequence[EpisodeJob],
        on_finish: FinishCallback,
        heartbeat: Callable[[], None] | None = None,
    ) -> None:
        """Run ``jobs`` (one per env, ``len(jobs) <= len(envs)``) to the end.

        ``heartbeat`` is called once per step (workers use it to exit when the parent died).
        """
        n = len(jobs)
        seed_global_rngs(jobs[0].seed)
        self.policy.reset(n)
        if isinstance(self.policy, SeededPolicy):  # per-episode noise, whatever the batch
            self.policy.seed_envs([job.seed for job in jobs])
        trackers = [EpisodeTracker(self.policy_dt, mass_key=self.mass_key) for _ in range(n)]
        self._settled_steps = [0] * n
        obs = [self._reset(i, job, trackers[i], on_finish) for i, job in enumerate(jobs)]
        while not all(t.done for t in trackers):
            if heartbeat is not None:
                heartbeat()
            try:
                actions = np.asarray(self.policy.act(stack_obs(obs)), dtype=np.float32)
                if actions.shape[0] != n:
                    raise ValueError(f"policy returned {actions.shape[0]} actions for {n} envs")
            except Exception as exc:  # noqa: BLE001 - recorded as the episodes' failure reason
                for i, tracker in enumerate(trackers):
                    if not tracker.done:
                        self._finish(i, tracker, _crash_reason(exc), on_finish)
                return
            skip = frames_unread(self.policy, n)
            for i, tracker in enumerate(trackers):
                if not tracker.done:
                    if skip[i]:
                        skip_images(self.envs[i])
                    obs[i] = self._step(i, actions[i], obs[i], tracker, on_finish)

    def _reset(
        self, i: int, job: EpisodeJob, tracker: EpisodeTracker, on_finish: FinishCallback
    ) -> dict[str, np.ndarray]:
        """Reset env ``i`` for ``job``; a failing reset ends the episode at length 0."""
        try:
            value = job.value if job.reset_value is None else job.reset_value
            obs, info = self.envs[i].reset(seed=job.seed, options={self.param_name: value})
            tracker.start(info)  # the mass and robot profile the env set up
            if not obs_is_finite(obs):
                raise SimulationError("non-finite observation after reset")
            self._record(i)
            return obs
        except Exception as exc:  # noqa: BLE001 - recorded as the episode's failure reason
            self._finish(i, tracker, _crash_reason(exc), on_finish)
            return _placeholder_obs(self.envs[i])

    def _step(
        self,
        i: int,
        action: np.ndarray,
        last_obs: dict[str, np.ndarray],
        tracker: EpisodeTracker,
        on_finish: FinishCallback,
    ) -> dict[str, np.ndarray]:
        """Step env ``i``; returns the observation to feed the policy next."""
        try:
            obs, _, terminated, truncated, info = self.envs[i].step(action)
            tracker.update(info)
            self._record(i)
            if not obs_is_finite(obs):
                raise SimulationError("non-finite observation")
        except Exception as exc:  # noqa: BLE001 - recorded as the episode's failure reason
            self._finish(i, tracker, _crash_reason(exc), on_finish)
            return last_obs
        if terminated or truncated:
            reason = str(info.get("failure_reason") or ("timeout" if truncated else "terminated"))
            self._finish(i, tracker, reason, on_finish)
        elif self.end_early and self._settled(i):
            self._finish(i, tracker, SETTLED_REASON, on_finish)
        return obs

    def _settled(self, i: int) -> bool:
        """Env ``i``'s outcome has been settled on every step of the last ``SETTLE_S``."""
        settled = getattr(self.envs[i].unwrapped, "outcome_settled", None)
        self._settled_steps[i] = self._settled_steps[i] + 1 \
            if callable(settled) and settled() else 0
        return self._settled_steps[i] * self.policy_dt >= SETTLE_S - 1e-9

    def _record(self, i: int) -> None:
        """Add env ``i``'s current frame to its video, if its episode is recorded."""
        video = self.videos.get(i)
        if video is not None:
            video.add(self.envs[i].render())

    def _finish(
        self, i: int, tracker: EpisodeTracker, reason: str, on_finish: FinishCallback
    ) -> None:
        """Close episode ``i``, tell the policy (optional ``finish_envs``), report its row."""
        tracker.finish(reason)
        video = self.videos.pop(i, None)
        if video is not None:
            video.close()
        if isinstance(self.policy, FinishingPolicy):  # stop computing discarded actions
            self.policy.finish_envs([i])
        columns = tracker.row()
        if self.with_press_diagnostics:
            columns.update(tracker.press_diagnostics())
        on_finish(i, columns)
