"""What a sweep's workers are handed: its configuration, its tasks and where rows go."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from impact_control.errors import ImpactError
from impact_envs.tasks.bins import bin_param_name, draw_in_bin
from impact_eval.grid import episode_seed
from impact_eval.rollout import EpisodeJob
from impact_eval.spec import RunOptions, SweepSpec

RowSink = Callable[[dict[str, object]], None]


class SweepError(ImpactError):
    """The sweep could not finish (a worker died or failed outside an episode)."""


@dataclass(frozen=True)
class SweepConfig:
    """Everything a worker needs (picklable): the spec, the run options, and what ``prepare``
    read from the env."""

    spec: SweepSpec
    """What defines the rows (``spec.py``)."""
    options: RunOptions
    """Where and how the sweep runs."""
    canonical_env_id: str
    """``env.spec.id``, written to the CSV."""
    param_name: str
    """The swept parameter, resolved (``spec.param`` or the env's first)."""
    policy_dt: float
    """The env's policy period [s]."""

    @property
    def row_param_name(self) -> str:
        """``param_name`` as the rows carry it (``object_mass_bin`` for a bin sweep)."""
        return bin_param_name(self.param_name) if self.spec.bin_highs else self.param_name

    @property
    def video_dir(self) -> Path:
        """Where the videos go (``OUT/videos``)."""
        return self.options.out / "videos"

    def job(self, value_index: int, episode: int) -> EpisodeJob:
        """Episode ``episode`` of the cell at ``values[value_index]``: its paired seed, and in a
        bin sweep the mass it draws in its bin."""
        spec = self.spec
        value = spec.values[value_index]
        seed = episode_seed(spec.seed, value_index, episode)
        if not spec.bin_highs:
            return EpisodeJob(value, seed, episode)
        return EpisodeJob(value, seed, episode,
                          draw_in_bin(value, spec.bin_highs[value_index], seed))


@dataclass(frozen=True)
class EpisodeBatch:
    """Up to ``envs_per_worker`` episodes of one (method, value) in lockstep, or a chain."""

    method: str
    value: float
    jobs: tuple[EpisodeJob, ...]
    """The episodes whose rows the task writes."""
    chain: tuple[EpisodeJob, ...] = ()
    """Carried methods: the cell's episodes 0 to the last of ``jobs``, in order on one env, the
    controller state carried from each into the next (``chain.py``); the rest are reruns."""
