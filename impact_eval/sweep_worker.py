"""A sweep's per-process worker: envs per controller and one policy per method, built on first
use, running one task (``EpisodeBatch``) at a time; the process plumbing is ``sweep.py``'s
(or ``sweep_ray.py``'s)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from impact_control.errors import InvalidArgumentError
from impact_control.policy import Policy
from impact_eval.chain import run_chain
from impact_eval.grid import format_value
from impact_eval.methods import MethodSpec, resolve_method
from impact_eval.rollout import EpisodeJob, LockstepBatch
from impact_eval.sweep_config import EpisodeBatch, RowSink, SweepConfig


def carried(method: str) -> bool:
    """Whether ``method`` runs its cells as carried chains (an unregistered name: no; the CLI
    and ``evaluate`` refuse those before planning)."""
    try:
        return resolve_method(method).carry
    except InvalidArgumentError:
        return False


class Worker:
    """Per-process state: envs per controller and one policy per method, built on first use."""

    def __init__(self, cfg: SweepConfig) -> None:
        from impact_eval.envs import import_env_module

        import_env_module(cfg.spec.env_id)
        self.cfg = cfg
        self.envs: dict[tuple, list[object]] = {}
        self.policies: dict[str, Policy] = {}
        self.warm: dict[tuple[str, float], object] = {}

    def _envs(self, spec: MethodSpec, n: int) -> list[object]:
        """At least ``n`` envs of the method's (controller, preset)."""
        from impact_eval.envs import method_env

        envs = self.envs.setdefault(spec.env_key(self.cfg.spec.env_id), [])
        while len(envs) < n:
            envs.append(method_env(self.cfg.spec.env_id, spec, self.cfg.spec.controller_overrides,
                                   render=self.cfg.options.video_episodes > 0,
                                   robot_overrides=self.cfg.spec.robot_overrides))
        return envs

    def _policy(self, method: str) -> Policy:
        if method not in self.policies:
            spec = resolve_method(method)
            env = self._envs(spec, 1)[0]
            self.policies[method] = spec.build(self.cfg.canonical_env_id, env)
        return self.policies[method]

    def run(self, task: EpisodeBatch, sink: RowSink,
            heartbeat: Callable[[], None] | None = None) -> None:
        """Run one task; ``sink`` receives each full CSV row as its episode ends."""
        spec = resolve_method(task.method)
        if spec.carry:
            run_chain(self, spec, task, sink, heartbeat)
            return
        envs = self._envs(spec, len(task.jobs))
        snapshot = self._warm_snapshot(spec, task.value) if spec.warm else None
        for env in envs:
            warm_start = getattr(env.unwrapped, "warm_start", None)  # type: ignore[attr-defined]
            if callable(warm_start):
                warm_start(snapshot)
        batch = LockstepBatch(envs, self._policy(task.method), self.cfg.param_name,
                              self.cfg.policy_dt, self._videos(task))
        batch.end_early = self.cfg.spec.end_early  # not in a carried chain (chain.py)

        def on_finish(i: int, metrics: dict[str, object]) -> None:
            sink(self.row(task.method, task.jobs[i], metrics))

        batch.run(task.jobs, on_finish, heartbeat)

    def row(self, method: str, job: EpisodeJob, metrics: dict[str, object]) -> dict[str, object]:
        """The CSV row of ``job``'s finished episode."""
        return {"method": method, "env_id": self.cfg.canonical_env_id,
                "param_name": self.cfg.row_param_name, "param_value": job.value, "seed": job.seed,
                "episode": job.episode, **metrics}

    def _videos(self, task: EpisodeBatch) -> dict[int, object]:
        """The task's episodes to record (episode index < ``video_episodes``), by batch index."""
        if not self.cfg.options.video_episodes:
            return {}
        from impact_eval.video import EpisodeVideo, video_path

        root = Path(self.cfg.video_dir)
        return {i: EpisodeVideo(video_path(root, task.method, self.cfg.param_name,
                                           format_value(job.value), job.episode))
                for i, job in enumerate(task.jobs) if job.episode < self.cfg.options.video_episodes}

    def _warm_snapshot(self, spec: MethodSpec, value: float) -> object:
        """The cell's warm-up snapshot (``warm.warm_up``), computed once per worker."""
        from impact_eval.warm import warm_up

        key = (spec.name, value)
        if key not in self.warm:
            self.warm[key] = warm_up(self._envs(spec, 1)[0], self._policy(spec.name),
                                     self.cfg.param_name, self.cfg.policy_dt, self.cfg.spec.seed,
                                     self.cfg.spec.values.index(value), value)
        return self.warm[key]

    def close(self) -> None:
        """Close every env."""
        for envs in self.envs.values():
            for env in envs:
                env.close()  # type: ignore[attr-defined]
