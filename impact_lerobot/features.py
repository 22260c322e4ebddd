"""Our observation dict as LeRobot's env keys, in the order of ``impact-export-lerobot``.

LeRobot 0.4.4's ``preprocess_observation`` reads ``agent_pos`` (to ``observation.state``),
``environment_state`` (to ``observation.environment_state``) and ``pixels`` (a dict of uint8
H x W x 3 images, to ``observation.images.<camera>``). Which of our entries go where, and in
which order, is the export's ``Layout`` (``impact_learn.lerobot_export.layout_of``) of the
entries a store of the same observation mode holds: a policy trained on an export gets the
same vectors from the plugin, value for value.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from impact_control.errors import ImpactError
from impact_learn.lerobot_layout import (
    ACTION_NAMES,
    ENV_STATE_FEATURE,
    IMAGE_FEATURE_PREFIX,
    STATE_FEATURE,
    Layout,
    entry_names,
    env_entries,
    layout_of,
)
from impact_lerobot.settings import PluginSettings

AGENT_POS, ENV_STATE, PIXELS, ACTION = "agent_pos", "environment_state", "pixels", "action"
VECTOR_KEYS = {STATE_FEATURE: AGENT_POS, ENV_STATE_FEATURE: ENV_STATE}
"""Export feature -> the env key LeRobot reads it from."""
ACTION_SIZE = len(ACTION_NAMES)


@dataclass(frozen=True)
class Feature:
    """One feature of the plugin's ``EnvConfig``.

    Attributes:
        env_key: Key in ``EnvConfig.features`` (``agent_pos``, ``pixels/wrist``, ``action``).
        policy_key: The policy's feature (``observation.state``, ...), ``features_map``'s value.
        kind: LeRobot's ``FeatureType`` name: ``STATE``, ``ENV``, ``VISUAL`` or ``ACTION``.
        shape: Per step (images H x W x 3, as LeRobot's env configs give them).
        names: What each value is (``ee_pos.0``, ...), as in the export's ``info.json``;
            None for images.
    """

    env_key: str
    policy_key: str
    kind: str
    shape: tuple[int, ...]
    names: tuple[str, ...] | None


@dataclass(frozen=True)
class ObservationPlan:
    """How one env's observation dict becomes LeRobot's.

    Attributes:
        layout: The export's layout of the observation entries.
        sizes: Values per vector entry.
        image_shape: H x W x 3 of every camera image.
    """

    layout: Layout
    sizes: dict[str, int]
    image_shape: tuple[int, int, int]

    def features(self) -> tuple[Feature, ...]:
        """The observation features in the export's order, then the action."""
        feats = []
        for name, keys in self.layout.vectors():
            names = tuple(entry_names(self.sizes, keys))
            kind = "STATE" if name == STATE_FEATURE else "ENV"
            feats.append(Feature(VECTOR_KEYS[name], name, kind, (len(names),), names))
        for name in self.layout.cameras:
            camera = name[len(IMAGE_FEATURE_PREFIX):]
            feats.append(Feature(f"{PIXELS}/{camera}", name, "VISUAL", self.image_shape, None))
        feats.append(Feature(ACTION, ACTION, "ACTION", (ACTION_SIZE,), tuple(ACTION_NAMES)))
        return tuple(feats)

    def cameras(self) -> dict[str, str]:
        """Camera name -> our observation key (``wrist`` -> ``wrist_rgb``)."""
        return {name[len(IMAGE_FEATURE_PREFIX):]: key
                for name, key in self.layout.cameras.items()}

    def convert(self, obs: dict[str, np.ndarray]) -> dict[str, object]:
        """Our observation dict as LeRobot's: float32 vectors, uint8 images."""
        out: dict[str, object] = {
            VECTOR_KEYS[name]: np.concatenate([np.asarray(obs[k]).ravel() for k in keys])
            .astype(np.float32)
            for name, keys in self.layout.vectors()}
        if self.layout.cameras:
            out[PIXELS] = {camera: obs[key] for camera, key in self.cameras().items()}
        return out

    def policy_batch(self, obs: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """A batch of our observation dicts (``{key: (B, ...)}``) as the policy's features,
        as LeRobot's ``preprocess_observation`` makes them from ``convert``'s output: float32
        vectors ``(B, d)``, images float32 ``(B, 3, H, W)`` in [0, 1]."""
        out = {name: np.concatenate([np.asarray(obs[k]).reshape(len(obs[k]), -1) for k in keys],
                                    axis=1).astype(np.float32)
               for name, keys in self.layout.vectors()}
        for name, key in self.layout.cameras.items():
            out[name] = np.ascontiguousarray(
                np.asarray(obs[key]).transpose(0, 3, 1, 2).astype(np.float32) / 255.0)
        return out

    def space(self, ours: spaces.Dict) -> spaces.Dict:
        """LeRobot's observation space from our env's (``ours``): vector bounds concatenated."""
        self.check(ours)
        entries: dict[str, spaces.Space] = {}
        for name, keys in self.layout.vectors():
            low, high = (np.concatenate([getattr(ours[k], b) for k in keys]) for b in
                         ("low", "high"))
            entries[VECTOR_KEYS[name]] = spaces.Box(low, high, dtype=np.float32)
        if self.layout.cameras:
            entries[PIXELS] = spaces.Dict({camera: ours[key]
                                           for camera, key in self.cameras().items()})
        return spaces.Dict(entries)

    def check(self, ours: spaces.Dict) -> None:
        """Our env's observation entries must be the plan's (a one-line ``ImpactError``)."""
        planned = {*self.layout.state_keys, *self.layout.env_keys,
                   *self.layout.cameras.values()}
        shapes_ok = all(ours[k].shape == (self.sizes[k],) for k in
                        (*self.layout.state_keys, *self.layout.env_keys) if k in ours.spaces)
        if set(ours.spaces) != planned or not shapes_ok:
            raise ImpactError(f"the env's observation entries {sorted(ours.spaces)} are not "
                              f"the LeRobot plugin's {sorted(planned)}; valid: the same entries")


def observation_plan(settings: PluginSettings) -> ObservationPlan:
    """The plan of ``settings``' env: the entries a store of its observation mode holds (the
    image modes' as ``impact_envs.envs.pixels`` builds them: ``rgb`` drops the task's
    privileged entries, ``state+rgb`` keeps them), laid out as the export lays them out."""
    entries = env_entries(settings.env_id)
    opts = settings.observation
    drop = entries.hidden if opts.obs_mode == "rgb" else ()
    ranks = {k: 1 for k in entries.order if k not in drop}
    if opts.uses_images:
        ranks.update({f"{camera}_rgb": 3 for camera in opts.cameras})
    shape = (int(opts.image_height), int(opts.image_width), 3)
    return ObservationPlan(layout_of(ranks, entries.order, entries.hidden), entries.sizes, shape)
