"""What a sweep's workers are handed: its configuration, its tasks and where rows go."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from impact_control.errors import ImpactError
from impact_eval.bins import bin_param_name, draw_in_bin
from impact_eval.grid import episode_seed
from impact_eval.rollout import EpisodeJob

RowSink = Callable[[dict[str, object]], None]


class SweepError(ImpactError):
    """The sweep could not finish (a worker died or failed outside an episode)."""


@dataclass(frozen=True)
class SweepConfig:
    """Everything a worker needs (picklable)."""

    env_id: str
    """Id as given on the CLI (may carry a ``module:`` prefix that registers it)."""
    canonical_env_id: str
    """``env.spec.id``, written to the CSV."""
    param_name: str
    policy_dt: float
    methods: tuple[str, ...]
    values: tuple[float, ...]
    episodes: int
    seed: int
    workers: int
    envs_per_worker: int
    controller_overrides: tuple[str, ...] = ()
    robot_overrides: tuple[str, ...] = ()
    """``--robot-set FIELD=VALUE`` on every method's robot (``RobotOptions`` fields)."""
    """``SECTION.FIELD=VALUE`` changes of the controller config (ablations; empty: paper's)."""
    video_episodes: int = 0
    """Record the first this many episodes of every cell as MP4 (``--video``)."""
    video_dir: str = ""
    """Where the videos go (``OUT/videos``)."""
    executor: str = "local"
    """``local`` (this machine's processes, ``workers`` of them) or ``ray`` (``sweep_ray``)."""
    ray_address: str | None = None
    """Ray cluster to join (``--ray-address``; None: ``$RAY_ADDRESS`` or a new local one)."""
    bin_highs: tuple[float, ...] = ()
    """``--mass-bins``: each bin's upper edge, ``values`` holding the lower edges (``bins.py``);
    empty: ``values`` is a grid of fixed values."""

    @property
    def row_param_name(self) -> str:
        """``param_name`` as the rows carry it (``object_mass_bin`` for a bin sweep)."""
        return bin_param_name(self.param_name) if self.bin_highs else self.param_name

    def job(self, value_index: int, episode: int) -> EpisodeJob:
        """Episode ``episode`` of the cell at ``values[value_index]``: its paired seed, and in a
        bin sweep the mass it draws in its bin."""
        value = self.values[value_index]
        seed = episode_seed(self.seed, value_index, episode)
        if not self.bin_highs:
            return EpisodeJob(value, seed, episode)
        return EpisodeJob(value, seed, episode,
                          draw_in_bin(value, self.bin_highs[value_index], seed))


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
