"""Options of ``impact-collect`` (demonstration collection with the scripted expert)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from impact_control.controller import CONTROLLERS
from impact_control.errors import InvalidArgumentError, check_choice
from impact_control.presets import PRESETS
from impact_envs.envs.options import ObservationOptions
from impact_envs.parallel import check_executor
from impact_envs.policies.experts import EXPERTS
from impact_envs.versions import check_not_retired

COMPENSATIONS = ("none", "closed_loop", "privileged")
"""Expert compensation modes (``impact_envs.policies.scripted.COMPENSATIONS``)."""


@dataclass(frozen=True)
class CollectConfig:
    """What to collect and where.

    At most one of ``param``, ``param_range`` and ``param_list`` is set; with none, the env's
    default parameter is used.

    Attributes:
        env_id: Gymnasium id, e.g. ``IMPACT/Hammer-v1``.
        out: Output zarr store path.
        episodes: Number of successful demonstrations to keep.
        param: Fixed value of the env's randomized parameter (object mass [kg]).
        param_range: ``(low, high)`` of a uniform draw per attempt.
        param_list: Values cycled over attempts (``values[attempt % len]``).
        compensation: How the expert meets a load's sag: ``none``, ``closed_loop`` (a
            teleoperator's integral on the observed height error) or ``privileged`` (m g / K
            from the mass; an ablation). ``policies/scripted.py``.
        expert: ``scripted`` (the task's expert) or ``authors`` (HammerBasket: the paper
            authors' demonstrator, ``policies/authors_demonstrator.py``; compensation
            ``privileged`` is their offset).
        controller: Low-level controller of the env: ``impedance`` or ``impact``.
        controller_preset: The controller's named configuration (``presets.PRESETS``):
            ``default``, or e.g. ``authors_sim``, whose impedance, limits and target filter
            are the authors' baselines' controller under ``controller="impedance"`` (issue 55).
        seed: Base seed; attempt k is seeded by ``(seed, k)``.
        post_success_steps: Steps recorded after the first step with ``info["is_success"]``
            before the attempt ends [policy steps] (envs need not terminate on success).
        n_envs: Envs stepped in lockstep (one batched expert call per step).
        max_attempts: Stop after this many attempts; None means ``3 * episodes + n_envs``.
        resume: Append to an existing store, continuing its attempt sequence.
        progress: Show a tqdm bar.
        executor: ``local`` (this process) or ``ray`` (each batch a Ray task:
            ``collect_ray``).
        ray_address: Ray cluster to join (None: ``$RAY_ADDRESS`` or a new local instance).
        observation: What the store keeps: ``obs_mode`` ``"state"`` (every state entry) or an
            image mode with its cameras and image size (``collect_pixels``; the expert acts
            on the full state either way).
    """

    env_id: str
    out: str
    episodes: int = 200
    param: float | None = None
    param_range: tuple[float, float] | None = None
    param_list: tuple[float, ...] | None = None
    compensation: str = "none"
    expert: str = "scripted"
    controller: str = "impedance"
    controller_preset: str = "default"
    seed: int = 0
    post_success_steps: int = 15
    n_envs: int = 8
    max_attempts: int | None = None
    resume: bool = False
    progress: bool = True
    executor: str = "local"
    ray_address: str | None = None
    observation: ObservationOptions = ObservationOptions()

    def __post_init__(self) -> None:
        check_not_retired(self.env_id)
        check_choice("controller", self.controller, CONTROLLERS)
        check_choice("controller preset", self.controller_preset, PRESETS)
        check_choice("compensation", self.compensation, COMPENSATIONS)
        check_choice("expert", self.expert, EXPERTS)
        check_executor(self.executor, self.ray_address)
        if not isinstance(self.observation, ObservationOptions):
            raise InvalidArgumentError(
                f"invalid observation {self.observation!r}; valid: an ObservationOptions")
        given = [x is not None for x in (self.param, self.param_range, self.param_list)]
        if sum(given) > 1:
            raise InvalidArgumentError("give at most one of --mass, --mass-range, --mass-list")
        for flag, value, low in (("--episodes", self.episodes, 1), ("--n-envs", self.n_envs, 1),
                                 ("--post-success-steps", self.post_success_steps, 0)):
            if value < low:
                raise InvalidArgumentError(f"{flag} must be >= {low}, got {value}")
        if self.seed < 0:
            raise InvalidArgumentError(f"--seed must be >= 0, got {self.seed}")
        if self.max_attempts is not None and self.max_attempts < 1:
            raise InvalidArgumentError(f"--max-attempts must be >= 1, got {self.max_attempts}")
        if self.param_range is not None and not self.param_range[0] <= self.param_range[1]:
            raise InvalidArgumentError(
                f"mass range must be LO:HI with LO <= HI: {self.param_range}"
            )
        if self.param_list is not None and not self.param_list:
            raise InvalidArgumentError("mass list must hold at least one value")

    @property
    def attempt_limit(self) -> int:
        """Maximum number of attempts (successful or not)."""
        if self.max_attempts is not None:
            return self.max_attempts
        return 3 * self.episodes + self.n_envs

    def param_spec(self) -> dict[str, Any]:
        """JSON description of the parameter distribution (stored in the zarr attrs)."""
        if self.param_range is not None:
            return {"mode": "uniform", "values": list(self.param_range)}
        if self.param_list is not None:
            return {"mode": "cycle", "values": list(self.param_list)}
        if self.param is not None:
            return {"mode": "fixed", "values": [self.param]}
        return {"mode": "env_default", "values": []}


def parse_param_spec(
    fixed: float | None, range_text: str | None, list_text: str | None
) -> tuple[float | None, tuple[float, float] | None, tuple[float, ...] | None]:
    """Parse ``--mass``, ``--mass-range LO:HI`` and ``--mass-list A,B,...``."""
    param_range = None
    if range_text is not None:
        parts = range_text.split(":")
        if len(parts) != 2:
            raise InvalidArgumentError(f"--mass-range must be LO:HI, got {range_text!r}")
        param_range = (_number(parts[0]), _number(parts[1]))
    param_list = None
    if list_text is not None:
        param_list = tuple(_number(p) for p in list_text.split(",") if p.strip())
    return fixed, param_range, param_list


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise InvalidArgumentError(f"expected a number, got {text!r}") from None
