"""Hyper-parameters of the Diffusion Policy baselines (state-based, or visuomotor with
``DiffusionConfig.vision`` set).

Defaults follow the CPU recipe (docs/diffusion_policy.md): Diffusion Policy's low-dim U-Net
recipe (Chi et al.) with a smaller net ``(64, 128, 256)`` and DDIM-10 sampling. Times are in
policy steps (1/30 s each).
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from impact_control.errors import InvalidArgumentError, check_choice

DEFAULT_OBS_KEYS: tuple[str, ...] = (
    "ee_pos",
    "ee_rot6d",
    "gripper_width",
    "object_pos",
    "object_rot6d",
    "goal_pos",
)
"""Observation keys the policy is conditioned on by default (joint states are left out)."""

BETA_SCHEDULES = ("squaredcos_cap_v2", "linear", "scaled_linear")
PREDICTION_TYPES = ("epsilon", "sample")
ACTION_XYZ_FRAMES = ("absolute", "delta_measured")


@dataclass(frozen=True)
class DiffusionConfig:
    """Network, diffusion and training hyper-parameters.

    Attributes:
        obs_keys: Env observation keys concatenated (in this order) into the state vector.
        n_obs_steps: To, number of past observations conditioning the policy [steps].
        horizon: Tp, length of the predicted action sequence [steps]; must be divisible by
            the U-Net's down-sampling factor ``2 ** (len(down_dims) - 1)``.
        n_action_steps: Ta, actions executed per prediction (receding horizon) [steps];
            ``Ta <= Tp - To + 1``.
        down_dims: Channels of the U-Net levels (one down-sampling between levels).
        kernel_size: Temporal convolution kernel size (odd).
        n_groups: GroupNorm groups; must divide every entry of ``down_dims``.
        diffusion_step_embed_dim: Size of the sinusoidal diffusion-step embedding.
        num_train_timesteps: Number of diffusion steps of the forward (noising) process.
        beta_schedule: diffusers beta schedule name.
        prediction_type: What the network predicts: ``epsilon`` (noise) or ``sample``.
        clip_sample: Clip the denoised sample to ``[-1, 1]`` (normalized action space).
        num_inference_steps: DDIM steps at rollout.
        binary_gripper: Execute the sign of the sampled gripper command (+1 closed, -1 open)
            instead of its value. For demonstrations whose gripper command is binary (every
            scripted expert here): a sample of, e.g., -0.6 half-closes the hand (the env maps
            the command to a finger position), the policy then sees a gripper width no demo
            shows and closes it further (docs/diffusion_policy.md). Set false for demonstrations
            with a graded gripper command. Sampling only; changing it needs no retraining.
        range_eps: Normalizer range below which a dimension counts as constant [data units].
        batch_size: Training windows per optimizer step.
        lr: Peak AdamW learning rate.
        betas: AdamW (beta1, beta2).
        weight_decay: AdamW decoupled weight decay.
        lr_warmup_steps: Linear warm-up length before the cosine decay [optimizer steps].
        ema_power: EMA decay exponent; decay = 1 - (1 + step / ema_inv_gamma) ** -ema_power.
        ema_inv_gamma: EMA decay step scale [optimizer steps].
        ema_min: Lower bound of the EMA decay.
        ema_max: Upper bound of the EMA decay.
        seed: Seed of weight initialization, batch sampling and training noise.
        action_xyz: What the action's xyz means: ``"absolute"``, the TCP target position in
            the world frame [m] (every shipped checkpoint); ``"delta_measured"``, an offset
            [m] added to the TCP position measured at the step it is executed, as the paper
            authors' released policy acts (docs/hammer_basket.md). Training subtracts each
            step's recorded ``ee_pos`` from its action; a changed value needs retraining.
        vision: Camera encoder of a visuomotor policy (``ImageEncoderConfig``; in JSON an
            object of its fields), or None for a state-based policy. With it, ``obs_keys`` are
            the robot's own entries and the cameras' features join them per step.
    """

    obs_keys: tuple[str, ...] = DEFAULT_OBS_KEYS
    n_obs_steps: int = 2
    horizon: int = 16
    n_action_steps: int = 8
    down_dims: tuple[int, ...] = (64, 128, 256)
    kernel_size: int = 5
    n_groups: int = 8
    diffusion_step_embed_dim: int = 64
    num_train_timesteps: int = 100
    beta_schedule: str = "squaredcos_cap_v2"
    prediction_type: str = "epsilon"
    clip_sample: bool = True
    num_inference_steps: int = 10
    binary_gripper: bool = True
    range_eps: float = 1e-4
    batch_size: int = 256
    lr: float = 1e-4
    betas: tuple[float, float] = (0.95, 0.999)
    weight_decay: float = 1e-6
    lr_warmup_steps: int = 500
    ema_power: float = 0.75
    ema_inv_gamma: float = 1.0
    ema_min: float = 0.0
    ema_max: float = 0.9999
    seed: int = 0
    action_xyz: str = "absolute"
    vision: ImageEncoderConfig | None = None

    def __post_init__(self) -> None:
        if isinstance(self.vision, dict):
            object.__setattr__(self, "vision", ImageEncoderConfig.from_dict(self.vision))
        if self.vision is not None and not isinstance(self.vision, ImageEncoderConfig):
            raise InvalidArgumentError(
                f"invalid DiffusionConfig field vision: {self.vision!r}; valid: null or an "
                "object of ImageEncoderConfig fields")
        object.__setattr__(self, "obs_keys", tuple(self.obs_keys))
        object.__setattr__(self, "down_dims", tuple(int(d) for d in self.down_dims))
        object.__setattr__(self, "betas", tuple(float(b) for b in self.betas))
        check_choice("beta_schedule", self.beta_schedule, BETA_SCHEDULES)
        check_choice("prediction_type", self.prediction_type, PREDICTION_TYPES)
        check_choice("action_xyz", self.action_xyz, ACTION_XYZ_FRAMES)
        self._check_positive()
        self._check_shapes()

    def _check_positive(self) -> None:
        names = ("n_obs_steps", "horizon", "n_action_steps", "kernel_size", "n_groups")
        names += ("diffusion_step_embed_dim", "num_train_timesteps", "num_inference_steps")
        names += ("batch_size",)
        for name in names:
            if getattr(self, name) < 1:
                raise InvalidArgumentError(f"{name} must be >= 1, got {getattr(self, name)}")
        if not isinstance(self.binary_gripper, bool):
            raise InvalidArgumentError(
                f"binary_gripper must be true or false, got {self.binary_gripper!r}"
            )
        if not self.obs_keys:
            raise InvalidArgumentError("obs_keys must name at least one observation key")
        if self.lr <= 0 or self.range_eps <= 0:
            raise InvalidArgumentError("lr and range_eps must be > 0")
        if not 0.0 <= self.ema_min <= self.ema_max <= 1.0:
            raise InvalidArgumentError("need 0 <= ema_min <= ema_max <= 1")
        if self.num_inference_steps > self.num_train_timesteps:
            raise InvalidArgumentError("num_inference_steps must be <= num_train_timesteps")

    def _check_shapes(self) -> None:
        if not self.down_dims:
            raise InvalidArgumentError("down_dims must have at least one level")
        if self.horizon % self.downsample_factor:
            raise InvalidArgumentError(
                f"horizon {self.horizon} must be divisible by {self.downsample_factor}"
                f" (2 ** (len(down_dims) - 1))"
            )
        if self.n_action_steps > self.horizon - self.n_obs_steps + 1:
            raise InvalidArgumentError(
                f"n_action_steps must be <= horizon - n_obs_steps + 1"
                f" = {self.horizon - self.n_obs_steps + 1}"
            )
        if self.kernel_size % 2 == 0:
            raise InvalidArgumentError(f"kernel_size must be odd, got {self.kernel_size}")
        if any(d % self.n_groups for d in self.down_dims):
            raise InvalidArgumentError(f"n_groups {self.n_groups} must divide every down_dim")

    @property
    def downsample_factor(self) -> int:
        """Temporal down-sampling of the U-Net bottleneck (``2 ** (levels - 1)``)."""
        return 2 ** (len(self.down_dims) - 1)

    def to_dict(self) -> dict[str, Any]:
        """Return a JSON-serialisable dict (tuples become lists). A state-based config has no
        ``vision`` entry and an absolute-action one no ``action_xyz`` entry, so its file reads
        as before those options existed."""
        out = {k: list(v) if isinstance(v, tuple) else v for k, v in self._items()}
        if self.action_xyz == "absolute":  # files from before the option read the same
            del out["action_xyz"]
        if self.vision is None:
            del out["vision"]
        else:
            out["vision"] = self.vision.to_dict()
        return out

    def _items(self) -> list[tuple[str, Any]]:
        return [(f.name, getattr(self, f.name)) for f in dataclasses.fields(self)]

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> DiffusionConfig:
        """Build a config from ``to_dict`` output; unknown keys raise InvalidArgumentError."""
        return _checked(cls, data, "DiffusionConfig keys", "")

    def to_json(self, path: str | Path) -> None:
        """Write the config as indented JSON to ``path``."""
        Path(path).write_text(json.dumps(self.to_dict(), indent=2) + "\n")

    @classmethod
    def from_json(cls, path: str | Path) -> DiffusionConfig:
        """Read a config written by ``to_json`` (one-line ``InvalidArgumentError`` if the file is
        missing, unreadable, not JSON or not a JSON object)."""
        try:
            data = json.loads(Path(path).read_text())
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise InvalidArgumentError(f"cannot read config {path}: {exc}") from None
        if not isinstance(data, dict):
            raise InvalidArgumentError(
                f"config {path} must be a JSON object of DiffusionConfig fields, "
                f"got {type(data).__name__}")
        return cls.from_dict(data)


@dataclass(frozen=True)
class ImageEncoderConfig:
    """Per-camera image encoder of the visuomotor policy (``vision.py``): Diffusion Policy's
    ResNet-style encoder with GroupNorm and spatial-softmax pooling, sized for CPU training.

    Attributes:
        image_keys: Store / observation keys of the cameras (``"<camera>_rgb"``), one encoder
            each (weights not shared).
        crop_ratio: Side of the random crop (training) and centre crop (rollout) as a fraction
            of the image side (DP: 84 of 96 px = 0.875).
        channels: Output channels of the stem and of each residual stage; every stage after the
            first halves the resolution (the stem halves it too).
        n_groups: GroupNorm groups; must divide every entry of ``channels``.
        keypoints: Spatial-softmax keypoints (2 coordinates each).
        feature_dim: Features per camera and observation step fed to the U-Net's condition.
    """

    image_keys: tuple[str, ...] = ("overview_rgb", "wrist_rgb")
    crop_ratio: float = 0.875
    channels: tuple[int, ...] = (16, 32, 64)
    n_groups: int = 8
    keypoints: int = 32
    feature_dim: int = 64

    def __post_init__(self) -> None:
        object.__setattr__(self, "image_keys", tuple(self.image_keys))
        object.__setattr__(self, "channels", tuple(int(c) for c in self.channels))
        if not self.image_keys or len(set(self.image_keys)) != len(self.image_keys):
            raise InvalidArgumentError(
                f"invalid image_keys {self.image_keys!r}; valid: distinct keys such as "
                "'overview_rgb', 'wrist_rgb'")
        if not 0.0 < self.crop_ratio <= 1.0:
            raise InvalidArgumentError(
                f"invalid crop_ratio {self.crop_ratio}; valid: 0 < crop_ratio <= 1")
        if not self.channels or min(self.channels) < 1:
            raise InvalidArgumentError(f"invalid channels {self.channels}; valid: integers >= 1")
        if self.n_groups < 1 or any(c % self.n_groups for c in self.channels):
            raise InvalidArgumentError(
                f"invalid n_groups {self.n_groups}; valid: a divisor of every channel count "
                f"{self.channels}")
        if self.keypoints < 1 or self.feature_dim < 1:
            raise InvalidArgumentError(
                f"invalid keypoints {self.keypoints} or feature_dim {self.feature_dim}; "
                "valid: >= 1")

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable fields (tuples become lists)."""
        return {f.name: list(v) if isinstance(v := getattr(self, f.name), tuple) else v
                for f in dataclasses.fields(self)}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ImageEncoderConfig:
        """Build from ``to_dict`` output; unknown keys or wrong types are one-line errors."""
        return _checked(cls, data, "vision keys", "vision.")

    def crop_size(self, height: int, width: int) -> tuple[int, int]:
        """Crop ``(height, width)`` [px] of an image of that size."""
        return (max(1, round(height * self.crop_ratio)), max(1, round(width * self.crop_ratio)))


def _kind(default: object, plural: bool = False) -> str:
    """What a field whose default is ``default`` accepts, in words."""
    if isinstance(default, bool):
        return "true or false"
    for kind, words in ((int, ("an integer", "integers")), (float, ("a number", "numbers")),
                        (str, ("a string", "strings"))):
        if isinstance(default, kind):
            return words[plural]
    return "a list"


def _type_ok(value: object, default: object) -> bool:
    if isinstance(default, bool):
        return isinstance(value, bool)
    if isinstance(default, int):
        return isinstance(value, int) and not isinstance(value, bool)
    if isinstance(default, float):
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if isinstance(default, str):
        return isinstance(value, str)
    if isinstance(default, tuple):
        if not isinstance(value, (list, tuple)):
            return False
        return not default or all(_type_ok(v, default[0]) for v in value)
    return True


def _check_field_type(name: str, value: object, default: object) -> None:
    """One-line error naming the field when ``value`` is not of the default's type."""
    if not _type_ok(value, default):
        element = f" of {_kind(default[0], True)}" if isinstance(default, tuple) and default else ""
        raise InvalidArgumentError(
            f"invalid DiffusionConfig field {name}: {value!r}; valid: {_kind(default)}{element}")


def _checked(cls: Any, data: dict[str, Any], what: str, prefix: str) -> Any:
    """``cls(**data)`` after one-line errors for unknown keys and ill-typed values (a field's
    type is its default's)."""
    names = [f.name for f in dataclasses.fields(cls)]
    unknown = sorted(set(data) - set(names))
    if unknown:
        raise InvalidArgumentError(f"unknown {what} {unknown}; valid keys: {', '.join(names)}")
    defaults = cls()
    for name, value in data.items():
        _check_field_type(f"{prefix}{name}", value, getattr(defaults, name))
    return cls(**data)
