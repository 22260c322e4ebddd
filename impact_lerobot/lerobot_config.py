"""The ``impact`` env type of LeRobot 0.4.4 (``--env.type=impact``); this module imports LeRobot.

LeRobot's ``--env.discover_packages_path=impact_lerobot`` imports the package and each of its
modules, this one among them, which registers ``ImpactEnv`` with LeRobot's ``EnvConfig``.
The fields are ``PluginSettings``' (same names, same defaults) plus LeRobot's own (``task``,
``fps``, ``features``, ``features_map``, ...); ``features`` and ``features_map`` are set from the
settings (``features.observation_plan``), whatever was given. The class is a plain (not frozen)
dataclass because LeRobot's ``EnvConfig`` is one; it hands its fields to the env as one frozen
``PluginSettings``.
"""

from dataclasses import dataclass, fields

from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.envs.configs import EnvConfig

from impact_control.errors import InvalidArgumentError
from impact_control.rates import POLICY_HZ
from impact_lerobot.features import observation_plan
from impact_lerobot.settings import PluginSettings

PACKAGE = "impact_lerobot"


@EnvConfig.register_subclass("impact")
@dataclass
class ImpactEnv(EnvConfig):
    """LeRobot's config of an IMPACT env: ``PluginSettings``' fields (docs/lerobot.md)."""

    task: str | None = PluginSettings.task
    fps: int = POLICY_HZ
    controller: str = PluginSettings.controller
    controller_preset: str = PluginSettings.controller_preset
    object_mass: float | None = PluginSettings.object_mass
    mass_bin: tuple[float, float] | None = PluginSettings.mass_bin
    obs_mode: str = PluginSettings.obs_mode
    cameras: tuple[str, ...] = PluginSettings.cameras
    image_width: int = PluginSettings.image_width
    image_height: int = PluginSettings.image_height
    episode_length: int | None = PluginSettings.episode_length

    def __post_init__(self) -> None:
        if self.fps != POLICY_HZ:
            raise InvalidArgumentError(f"invalid fps {self.fps!r}; valid: {POLICY_HZ} (the "
                                       "IMPACT envs' policy rate)")
        feats = observation_plan(self.settings).features()
        self.features = {f.env_key: PolicyFeature(FeatureType[f.kind], f.shape) for f in feats}
        self.features_map = {f.env_key: f.policy_key for f in feats}

    @property
    def settings(self) -> PluginSettings:
        """The fields as the plugin's settings (checked: a one-line error on a bad value)."""
        return PluginSettings(**{f.name: getattr(self, f.name) for f in fields(PluginSettings)})

    @property
    def package_name(self) -> str:
        """What LeRobot imports when ``gym_id`` is not registered: this package, which
        registers it."""
        return PACKAGE

    @property
    def gym_id(self) -> str:
        return self.settings.gym_id

    @property
    def gym_kwargs(self) -> dict:
        """``gym.make``'s arguments: the settings, ``rgb_array`` rendering (LeRobot's eval
        videos) and the episode length."""
        settings = self.settings
        return {"settings": settings, "render_mode": "rgb_array",
                "max_episode_steps": settings.steps}
