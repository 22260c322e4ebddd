"""What an ``impact`` env of the LeRobot plugin runs: task, controller, object mass, observation.

``PluginSettings`` is the plugin's configuration without LeRobot: the LeRobot config class
(``lerobot_config.ImpactEnv``) holds the same fields for LeRobot's command line and hands them
over as one ``PluginSettings``, which the wrapped env (``env.make_lerobot_env``) is made from.
Every bad value is a one-line ``InvalidArgumentError`` naming the valid choices.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real

from impact_control.controller import CONTROLLERS
from impact_control.errors import InvalidArgumentError, check_choice
from impact_control.presets import PRESETS
from impact_envs import ENV_IDS, REGISTERED_IDS, ObservationOptions
from impact_envs.tasks.base import Task, TaskParam
from impact_envs.tasks.bins import mass_param_name
from impact_envs.tasks.registry import task_class
from impact_envs.versions import check_not_retired

GYM_NAMESPACE = "gym_impact"
"""LeRobot 0.4.4 makes ``gym_<type>/<task>``: the wrapped envs are registered under it."""
ENV_NAMESPACE = "IMPACT"
TASKS: tuple[str, ...] = tuple(env_id.split("/", 1)[1] for env_id in REGISTERED_IDS)
"""The plugin's tasks: one per registered built-in env version (``Hammer-v2`` is
``IMPACT/Hammer-v2``; the kept ``-v1`` ids too)."""
OBS_MODES: tuple[str, ...] = ("state", "rgb", "state+rgb")
"""The observation modes ``impact-export-lerobot`` exports (``rgbd``'s depth images are not
exported, docs/lerobot.md), so a policy trained on an export sees the same features here."""


def mass_param(task: type[Task]) -> TaskParam:
    """The task parameter a mass setting sets: the one the task declares ``is_mass``
    (Calligraphy: ``tool_mass``), the one ``impact-eval --mass-bins`` draws
    (``bins.mass_param_name``; on Disturbance with ``--param object_mass``)."""
    name = mass_param_name(task.params)
    if name is None:
        raise InvalidArgumentError(f"{task.name} has no mass parameter; valid parameters: "
                                   f"{', '.join(p.name for p in task.params)}")
    return next(p for p in task.params if p.name == name)


@dataclass(frozen=True)
class PluginSettings:
    """One ``impact`` env for LeRobot.

    Attributes:
        task: One of ``TASKS`` (``Hammer-v2``, the default, runs ``IMPACT/Hammer-v2``).
        controller: ``impact`` (IMPACT) or ``impedance`` (the plain impedance baseline).
        controller_preset: One of ``impact_control.presets.PRESETS``.
        object_mass: The mass [kg] of every episode (the task's ``mass_param``); None: the
            task's default, unless ``mass_bin`` is given.
        mass_bin: ``(lo, hi)`` [kg]: each episode draws its mass uniformly in ``[lo, hi)``
            from its reset seed, as ``impact-eval --mass-bins`` does (``bins.draw_in_bin``).
        obs_mode: One of ``OBS_MODES``.
        cameras: Cameras of the image modes (one ``observation.images.<camera>`` each).
        image_width, image_height: Camera image size [px].
        episode_length: Policy steps per episode, at most the env's; None: the env's.
    """

    task: str = ENV_IDS[0].split("/", 1)[1]
    controller: str = "impact"
    controller_preset: str = "default"
    object_mass: float | None = None
    mass_bin: tuple[float, float] | None = None
    obs_mode: str = "state"
    cameras: tuple[str, ...] = ObservationOptions.cameras
    image_width: int = ObservationOptions.image_width
    image_height: int = ObservationOptions.image_height
    episode_length: int | None = None

    def __post_init__(self) -> None:
        check_not_retired(f"gym_impact/{self.task}")
        check_choice("task", self.task, TASKS)
        check_choice("controller", self.controller, CONTROLLERS)
        check_choice("controller_preset", self.controller_preset, PRESETS)
        check_choice("obs_mode", self.obs_mode, OBS_MODES)
        for name in ("cameras", "mass_bin"):  # lists, e.g. from LeRobot's command line
            if isinstance(getattr(self, name), list):
                object.__setattr__(self, name, tuple(getattr(self, name)))
        self.observation  # noqa: B018 - ObservationOptions checks cameras and image size
        self._check_mass()
        self._check_length()

    def _check_mass(self) -> None:
        param = mass_param(self.task_class)
        if self.object_mass is not None and self.mass_bin is not None:
            raise InvalidArgumentError("invalid mass: object_mass and mass_bin both given; "
                                       "valid: one of them, or neither (the task's default)")
        if self.object_mass is not None:
            param.validate(self.object_mass)
        if self.mass_bin is None:
            return
        edges = self.mass_bin
        if (not isinstance(edges, tuple) or len(edges) != 2
                or not all(isinstance(e, Real) and not isinstance(e, bool) for e in edges)
                or not all(math.isfinite(float(e)) for e in edges) or not edges[0] < edges[1]):
            raise InvalidArgumentError(
                f"invalid mass_bin {edges!r}; valid: two numbers (lo, hi) in kg with lo < hi, "
                f"within {param.low:g} to {param.high:g}")
        for edge in edges:
            param.validate(edge)

    def _check_length(self) -> None:
        steps, most = self.episode_length, self.task_class.max_episode_steps
        if steps is not None and (isinstance(steps, bool) or not isinstance(steps, int)
                                  or not 1 <= steps <= most):
            raise InvalidArgumentError(
                f"invalid episode_length {steps!r}; valid: an integer from 1 to {most} "
                f"({self.task}'s episode), or None for {most}")

    @property
    def env_id(self) -> str:
        """Our env's id (``IMPACT/Hammer-v1``)."""
        return f"{ENV_NAMESPACE}/{self.task}"

    @property
    def gym_id(self) -> str:
        """The wrapped env's id, as LeRobot 0.4.4 makes it (``gym_impact/Hammer-v1``)."""
        return f"{GYM_NAMESPACE}/{self.task}"

    @property
    def task_class(self) -> type[Task]:
        return task_class(self.env_id)

    @property
    def steps(self) -> int:
        """Policy steps per episode."""
        return self.episode_length or self.task_class.max_episode_steps

    @property
    def observation(self) -> ObservationOptions:
        return ObservationOptions(obs_mode=self.obs_mode, cameras=self.cameras,
                                  image_width=self.image_width, image_height=self.image_height)
