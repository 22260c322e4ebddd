"""Pixel observations: camera images in the observation ``Dict`` (``ObservationOptions``).

In the image modes (``"rgb"``, ``"rgbd"``, ``"state+rgb"``) the env renders each named camera
once per policy step, in ``reset`` and ``step``, with one offscreen ``mujoco.Renderer`` of the
image size (made at the first observation, reused, closed by ``env.close()``). Keys:
``"<camera>_rgb"`` uint8 (H, W, 3) in [0, 255] and, in ``"rgbd"``, ``"<camera>_depth"``
float32 (H, W, 1): distance along the camera's optical axis [m], from 0 to the scene's far
clipping plane (nothing in view reads as the far plane). Sites (markers such as the TCP)
are not drawn. ``"rgb"`` and ``"rgbd"`` drop the task's privileged entries
(``Task.privileged_observations``): the policy sees the cameras, the robot's own sensors and
the task's commands only. ``"state"`` builds nothing here.

A reader that will not look at the next observation's images (a diffusion policy between
replans: ``Policy.frames_read_next``) may say so with ``ImpactEnv.skip_next_images``: that
observation then holds zero images and ``info["images_rendered"]`` is False. ``reset`` always
renders.
"""

from __future__ import annotations

import mujoco
import numpy as np
from gymnasium import spaces

from impact_control.errors import InvalidArgumentError, check_choice
from impact_envs._gl import check_rendering, make_renderer
from impact_envs.envs.options import ObservationOptions
from impact_envs.tasks.base import Task


def scene_cameras(model: mujoco.MjModel) -> list[str]:
    """Names of the scene's cameras, in model order."""
    return [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_CAMERA, i) for i in range(model.ncam)]


def privileged_keys(task: Task) -> tuple[str, ...]:
    """The task entries the image modes leave out (all of them when the task declares none)."""
    names = tuple(e.name for e in task.observations)
    declared = task.privileged_observations
    if declared is None:
        return names
    unknown = [k for k in declared if k not in names]
    if unknown:
        raise InvalidArgumentError(
            f"{task.name}: privileged_observations {unknown} are not observation entries; "
            f"valid: {', '.join(names)}")
    return tuple(declared)


def check_view(model: mujoco.MjModel, what: str, cameras: tuple[str, ...], width: int,
               height: int) -> None:
    """One-line errors unless every camera is one of the scene's and the ``what`` size
    ("render size", "image size") fits the scene's offscreen buffer."""
    valid = scene_cameras(model)
    for camera in cameras:
        check_choice("camera", camera, valid)
    gl = model.vis.global_
    if width > gl.offwidth or height > gl.offheight:
        raise InvalidArgumentError(
            f"invalid {what} {width}x{height}; valid: at most {gl.offwidth}x{gl.offheight} px "
            "(the scene's offscreen buffer, <global offwidth offheight> in the scene XML)")


def far_clip_m(model: mujoco.MjModel) -> float:
    """Distance of the far clipping plane [m]: the largest depth a camera reports."""
    return float(model.vis.map.zfar * model.stat.extent)


class PixelObservations:
    """Builds the image modes' observation space and observations for one env.

    Args:
        model: the env's compiled scene.
        task: the env's task (its privileged entries are dropped in ``"rgb"``/``"rgbd"``).
        opts: validated options in an image mode.
        state_space: the env's ``"state"`` observation space.
    """

    def __init__(self, model: mujoco.MjModel, task: Task, opts: ObservationOptions,
                 state_space: spaces.Dict) -> None:
        check_view(model, "image size", opts.cameras, opts.image_width, opts.image_height)
        check_rendering()  # a machine that cannot render fails here, in one line
        self.model, self.cameras = model, opts.cameras
        self.depth = opts.obs_mode == "rgbd"
        self.size = (int(opts.image_height), int(opts.image_width))
        self.shadows = opts.shadows
        hidden = () if opts.obs_mode == "state+rgb" else privileged_keys(task)
        self.state_keys = tuple(k for k in state_space.spaces if k not in hidden)
        self.far_m = far_clip_m(model)
        self.space = spaces.Dict({**{k: state_space[k] for k in self.state_keys},
                                  **self._image_spaces()})
        self._renderer: mujoco.Renderer | None = None
        self._option = mujoco.MjvOption()
        self._option.sitegroup[:] = 0  # sites are markers for people, not things a camera sees
        self._skip = False
        self.rendered = True
        """Whether the latest observation's images were rendered (False: ``skip_next``)."""

    def _image_spaces(self) -> dict[str, spaces.Box]:
        h, w = self.size
        boxes: dict[str, spaces.Box] = {}
        for camera in self.cameras:
            boxes[f"{camera}_rgb"] = spaces.Box(0, 255, (h, w, 3), dtype=np.uint8)
            if self.depth:
                boxes[f"{camera}_depth"] = spaces.Box(0.0, self.far_m, (h, w, 1),
                                                      dtype=np.float32)
        return boxes

    def skip_next(self) -> None:
        """The next observation carries zero images instead of rendered ones (its reader
        declared it will not look: ``Policy.frames_read_next``); the one after renders again."""
        self._skip = True

    def render_next(self) -> None:
        """Undo ``skip_next``: the next observation is rendered."""
        self._skip = False

    def _blank(self) -> dict[str, np.ndarray]:
        return {k: np.zeros(box.shape, box.dtype) for k, box in self._image_spaces().items()}

    def render(self, data: mujoco.MjData) -> dict[str, np.ndarray]:
        """One image per camera (and a depth image each in ``"rgbd"``) of ``data`` now."""
        if self._renderer is None:
            h, w = self.size
            self._renderer = make_renderer(self.model, h, w)  # no GL: one-line RenderingError
            self._renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = self.shadows
        renderer, images = self._renderer, {}
        for camera in self.cameras:
            renderer.update_scene(data, camera=camera, scene_option=self._option)
            images[f"{camera}_rgb"] = renderer.render()
            if self.depth:
                renderer.enable_depth_rendering()
                depth = renderer.render()
                renderer.disable_depth_rendering()
                depth = np.clip(depth, 0.0, self.far_m).astype(np.float32, copy=False)
                images[f"{camera}_depth"] = depth[..., None]
        return images

    def observe(self, state_obs: dict[str, np.ndarray],
                data: mujoco.MjData) -> dict[str, np.ndarray]:
        """The image mode's observation: the kept state entries and this step's images, in
        the order of ``space``."""
        images = self._blank() if self._skip else self.render(data)
        self.rendered, self._skip = not self._skip, False
        obs = {**{k: state_obs[k] for k in self.state_keys}, **images}
        return {k: obs[k] for k in self.space.spaces}

    def close(self) -> None:
        """Free the renderer (a later observation makes a new one)."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
