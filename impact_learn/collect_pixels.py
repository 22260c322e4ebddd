"""Image collection (``impact-collect --obs-mode rgb|rgbd|state+rgb``): the scripted expert acts
on the full state while the store receives what a policy in the chosen mode observes.

The env is made in ``"state"`` mode (its physics, random draws and state observations are those
of a state collection) and ``CameraView`` adds the chosen mode's images, rendered by the env's
own ``PixelObservations`` code after each ``reset`` and ``step``, i.e. the images the env made
with ``observation=ObservationOptions(obs_mode=...)`` returns for the same seed and actions.
The expert sees the state entries plus the images; the store keeps ``stored_space``'s keys
(the mode's observation: privileged entries dropped in ``"rgb"``/``"rgbd"``).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from impact_control.errors import InvalidArgumentError
from impact_envs.envs.options import ObservationOptions
from impact_envs.envs.pixels import PixelObservations
from impact_learn.dataset import FieldDims, ImageSpec


class CameraView(gym.Wrapper):
    """A state-mode IMPACT env whose observations also hold ``opts``'s camera images.

    Args:
        env: an env made in ``"state"`` mode (``gym.make`` of an IMPACT id, maybe wrapped).
        opts: the image mode, cameras and size to record.
    """

    def __init__(self, env: gym.Env, opts: ObservationOptions) -> None:
        super().__init__(env)
        base = env.unwrapped
        if not hasattr(base, "sim") or not hasattr(base, "task"):
            raise InvalidArgumentError(
                f"--obs-mode {opts.obs_mode} needs an IMPACT MuJoCo env; valid: --obs-mode state")
        state_space = env.observation_space
        if any(len(box.shape) == 3 for box in state_space.spaces.values()):
            raise InvalidArgumentError(
                "CameraView needs an env made in 'state' mode; valid: gym.make without "
                "observation=ObservationOptions(...)")
        self.pixels = PixelObservations(base.sim.model, base.task, opts, state_space)
        self.stored_space: spaces.Dict = self.pixels.space
        """The chosen mode's observation space: the keys the store keeps."""
        images = {k: s for k, s in self.pixels.space.spaces.items()
                  if k not in state_space.spaces}
        self.observation_space = spaces.Dict({**state_space.spaces, **images})

    rendering: bool = True
    """Whether observations carry the images; ``collect_run.run_screened`` turns it off for
    the first, state-only run of a batch's attempts."""

    def _with_images(self, obs: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        if not self.rendering:
            return obs
        return {**obs, **self.pixels.render(self.env.unwrapped.sim.data)}

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[dict, dict]:
        obs, info = self.env.reset(seed=seed, options=options)
        return self._with_images(obs), info

    def step(self, action: np.ndarray) -> tuple[dict, float, bool, bool, dict]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        return self._with_images(obs), reward, terminated, truncated, info

    def close(self) -> None:
        self.pixels.close()
        super().close()


def with_cameras(make_env: Callable[[], gym.Env],
                 opts: ObservationOptions) -> Callable[[], gym.Env]:
    """``make_env`` whose env is wrapped in ``CameraView`` (unchanged in ``"state"`` mode)."""
    if not opts.uses_images:
        return make_env

    def make() -> gym.Env:
        return CameraView(make_env(), opts)

    return make


def stored_dims(env: gym.Env) -> FieldDims:
    """What the store keeps of ``env``'s observation: ``{key: d}`` of flat entries and an
    ``ImageSpec`` of each image (a ``CameraView`` keeps only its mode's keys)."""
    space = env.stored_space if isinstance(env, CameraView) else env.observation_space
    dims: dict[str, int | ImageSpec] = {}
    for key, box in space.spaces.items():
        if len(box.shape) == 3:
            h, w, c = (int(n) for n in box.shape)
            dims[key] = ImageSpec((h, w, c), np.dtype(box.dtype).name)
        else:
            dims[key] = int(np.prod(box.shape))
    return dims


def observation_attrs(opts: ObservationOptions) -> dict[str, Any]:
    """The store attribute ``observation`` of an image collection (JSON)."""
    return {"obs_mode": opts.obs_mode, "cameras": list(opts.cameras),
            "image_width": int(opts.image_width), "image_height": int(opts.image_height),
            "shadows": bool(opts.shadows)}


def add_observation_arguments(parser: argparse.ArgumentParser) -> None:
    """``impact-collect``'s image options (``ObservationOptions`` fields)."""
    parser.add_argument("--obs-mode", default="state",
                        help="what the store keeps: state | rgb | rgbd | state+rgb "
                             "(docs/diffusion_policy.md)")
    parser.add_argument("--cameras", default="overview,wrist",
                        help="comma-separated cameras of the image modes: overview, front, "
                             "side, wrist")
    parser.add_argument("--image-width", type=int, default=96, help="image width [px]")
    parser.add_argument("--image-height", type=int, default=96, help="image height [px]")
    parser.add_argument("--no-shadows", action="store_true",
                        help="render without shadows (cheaper on a CPU renderer)")


def observation_from_args(args: argparse.Namespace) -> ObservationOptions:
    """``ObservationOptions`` of parsed ``impact-collect`` arguments (validated)."""
    cameras = tuple(c.strip() for c in args.cameras.split(",") if c.strip())
    return ObservationOptions(obs_mode=args.obs_mode, cameras=cameras,
                              image_width=args.image_width, image_height=args.image_height,
                              shadows=not args.no_shadows)
