"""Grouped constructor options of the IMPACT envs: the simulated robot, rendering and
observations."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields, replace
from numbers import Integral, Real

from impact_control.errors import InvalidArgumentError, check_choice
from impact_envs.robot.hand import HANDS, check_grasp_force, check_hand
from impact_envs.robot.realism import REALISMS as REALISMS  # re-exported
from impact_envs.robot.realism import Realism
from impact_envs.robot.sim import TORQUE_READINGS as TORQUE_READINGS  # re-exported
from impact_envs.robot.sim import check_torque_reading

LARGEST_HAND = max(HANDS, key=lambda name: HANDS[name].max_force_n)
"""The hand with the largest grasp force: ``RobotOptions`` without a hand checks against it
(the env checks the task's hand)."""

MAX_RENDER_PX = 4096
"""Largest render width or height [px] (the scenes' offscreen buffer is sized to match)."""


def _real(name: str, value: object, low: float, high: float, unit: str) -> None:
    """One-line error unless ``value`` is a real number (not a bool) in [low, high]."""
    if isinstance(value, bool) or not isinstance(value, Real) or not (
            math.isfinite(float(value)) and low <= float(value) <= high):
        raise InvalidArgumentError(f"invalid {name} {value!r}; valid: a number from {low:g} to "
                                   f"{high:g}{unit}")


def _pixels(name: str, value: object) -> None:
    """One-line error unless ``value`` is an integer image size from 1 to MAX_RENDER_PX."""
    if isinstance(value, bool) or not isinstance(value, Integral) or not (
            1 <= value <= MAX_RENDER_PX):
        raise InvalidArgumentError(
            f"invalid {name} {value!r}; valid: an integer from 1 to {MAX_RENDER_PX} px")


REALISM_FIELDS = ("tau_offset_std_nm", "tau_offset_drift_nm_per_sqrt_s", "model_link_mass_std",
                  "model_com_std_m", "model_inertia_std", "model_seed", "delay_ticks",
                  "command_loss_rate", "encoder_step_rad")
"""``RobotOptions`` fields that override one value of the realism profile each."""


@dataclass(frozen=True)
class RobotOptions:
    """The simulated robot (``gym.make(id, robot=RobotOptions(...))``).

    Attributes:
        sensor_noise: Encoder and joint-torque noise on (docs/sensing.md) or all zero.
        grasp_force_n: Gripper squeeze force when closing on an object [N], above 0 and at
            most the hand's largest (``robot/hand.py``: 140 N, the Franka Hand's quoted peak
            force; 200 N for ``"authors_sim"``). None (default): the hand's default (70 N for
            the Franka Hand; 200 N for ``"authors_sim"``).
        hand: Which hand's grasp-force range applies, one of ``hand.HANDS``
            (``"franka_hand"``, ``"authors_sim"``). None (default): the task's
            (``Task.hand``: the Franka Hand, except ``IMPACT/HammerBasket-v1``).
        model_mass_error: Relative error of the controller's link masses (0: exact model).
        torque_reading: What the controller reads as the measured joint torque, one of
            ``TORQUE_READINGS`` (docs/sensing.md, "Torque reading"):

            - ``"link_side"`` (default): the link-side joint-torque sensors, i.e. motor torque
              + joint damping + dof Coulomb friction, plus a per-episode bias and white noise
              (``sensor_noise``). Joint friction is inside the reading, so the wrench estimator
              sees only external forces.
            - ``"commanded"``: the torque the drives applied (MuJoCo ``qfrc_actuator`` of the
              arm: the command after the drives' torque-limit clip), with no torque-sensor
              noise and no bias: an echo of the command, not a sensor (the paper authors'
              simulation). Encoder noise on q / dq is unchanged (``sensor_noise``). Joint
              damping and Coulomb friction then read as external forces to the estimator.
        realism: The robot profile, one of ``REALISMS`` (``robot/realism.py``,
            docs/sensing.md "Realism profiles"): ``"ideal"`` (every result before issue 39,
            bit for bit) or ``"fr3"`` (an averaged dynamics model, drifting torque-sensor
            offsets, a one-tick delay, quantized encoders). None (default): the env
            version's (``impact_envs/versions.py``): ``"fr3"`` on the ``-v2`` envs,
            ``"ideal"`` on ``-v1`` and on HammerBasket at every version.
        tau_offset_std_nm: One field of the profile (``Realism``'s attributes give units and
            meaning), as are the eight fields after it: ``tau_offset_drift_nm_per_sqrt_s``,
            ``model_link_mass_std``, ``model_com_std_m``, ``model_inertia_std``,
            ``model_seed``, ``delay_ticks``, ``command_loss_rate`` and ``encoder_step_rad``.
            None (default): the profile's value; an explicit value overrides the profile.
    """

    sensor_noise: bool = True
    grasp_force_n: float | None = None
    model_mass_error: float = 0.0
    torque_reading: str = "link_side"
    hand: str | None = None
    realism: str | None = None
    tau_offset_std_nm: float | None = None
    tau_offset_drift_nm_per_sqrt_s: float | None = None
    model_link_mass_std: float | None = None
    model_com_std_m: float | None = None
    model_inertia_std: float | None = None
    model_seed: int | None = None
    delay_ticks: int | None = None
    command_loss_rate: float | None = None
    encoder_step_rad: float | None = None

    def __post_init__(self) -> None:
        self.resolved_realism()  # one line on an unknown profile or a bad field
        if not isinstance(self.sensor_noise, bool):
            raise InvalidArgumentError(
                f"invalid sensor_noise {self.sensor_noise!r}; valid: True or False")
        if self.hand is not None:
            check_hand(self.hand)
        if self.grasp_force_n is not None:  # against the task's hand again in the env
            check_grasp_force(self.grasp_force_n, self.hand or LARGEST_HAND)
        _real("model_mass_error", self.model_mass_error, -0.9, 10.0, "")
        check_torque_reading(self.torque_reading)

    def with_default_realism(self, profile: str) -> RobotOptions:
        """These options with ``realism`` set to ``profile`` if it is unset (the env's version
        chooses it)."""
        return self if self.realism is not None else replace(self, realism=profile)

    def resolved_realism(self, unset: str = "ideal") -> Realism:
        """The profile ``realism`` (``unset`` if it is None) with this option's explicit
        fields on top."""
        profile = unset if self.realism is None else self.realism
        if not isinstance(profile, str):
            raise InvalidArgumentError(
                f"invalid realism {self.realism!r}; valid choices: {', '.join(REALISMS)}")
        return Realism.resolve(profile, **{name: getattr(self, name)
                                           for name in REALISM_FIELDS})

    def grasp(self, task_hand: str) -> tuple[str, float]:
        """``(hand, grasp force [N])`` on a task whose hand is ``task_hand``: this option's
        hand, else the task's; this option's force, else that hand's default (one-line
        ``InvalidArgumentError`` if the force exceeds that hand's largest)."""
        hand = self.hand or task_hand
        force = HANDS[hand].default_force_n if self.grasp_force_n is None else self.grasp_force_n
        check_grasp_force(force, hand)
        return hand, float(force)


@dataclass(frozen=True)
class RenderOptions:
    """Offscreen rendering (``render_mode="rgb_array"``): image size [px] and camera name
    (``"overview"``, which frames the arm, the objects and the goal, ``"front"`` or ``"side"``,
    defined in assets/common.xml, or ``"wrist"`` on the hand,
    impact_control/assets/fr3_hand.xml)."""

    width: int = 320
    height: int = 240
    camera: str = "overview"

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            _pixels(f"render {name}", getattr(self, name))
        if not isinstance(self.camera, str) or not self.camera:
            raise InvalidArgumentError(
                f"invalid camera {self.camera!r}; valid: a camera name of the scene, e.g. "
                "'overview', 'front', 'side'")


OBS_MODES = ("state", "rgb", "rgbd", "state+rgb")
"""``"state"``: the robot's and the task's entries (default); ``"rgb"``: the robot's own
entries (and task entries a camera cannot replace) plus one RGB image per camera;
``"rgbd"``: as ``"rgb"`` plus one depth image per camera; ``"state+rgb"``: every state entry
plus the RGB images (privileged, e.g. for an asymmetric critic). docs/envs.md."""


@dataclass(frozen=True)
class ObservationOptions:
    """What the policy observes (``gym.make(id, observation=ObservationOptions(...))``).

    Attributes:
        obs_mode: One of ``OBS_MODES``.
        cameras: Camera names rendered in the image modes, one image per camera and mode
            (``"overview"``, ``"front"``, ``"side"`` in assets/common.xml, ``"wrist"`` on the
            hand in impact_control/assets/fr3_hand.xml); ignored in ``"state"`` mode.
        image_width, image_height: Image size [px] (at most the scene's 640x480 buffer).
        shadows: Draw shadows (as ``render()`` does). On a CPU renderer they are most of the
            cost of an image (``impact-bench --pixels``, docs/envs.md).
    """

    obs_mode: str = "state"
    cameras: tuple[str, ...] = ("overview", "wrist")
    image_width: int = 96
    image_height: int = 96
    shadows: bool = True

    def __post_init__(self) -> None:
        if self.obs_mode not in OBS_MODES:
            raise InvalidArgumentError(
                f"invalid obs_mode {self.obs_mode!r}; valid choices: {', '.join(OBS_MODES)}")
        cams = self.cameras
        if isinstance(cams, list):  # e.g. from a dict read from JSON or YAML
            cams = tuple(cams)
            object.__setattr__(self, "cameras", cams)
        if (not isinstance(cams, tuple) or not cams or len(set(cams)) != len(cams)
                or not all(isinstance(c, str) and c for c in cams)):
            raise InvalidArgumentError(
                f"invalid cameras {cams!r}; valid: a tuple of distinct camera names, e.g. "
                "('overview', 'side', 'wrist')")
        for name in ("image_width", "image_height"):
            _pixels(name, getattr(self, name))
        if not isinstance(self.shadows, bool):
            raise InvalidArgumentError(f"invalid shadows {self.shadows!r}; valid: True or False")

    @property
    def uses_images(self) -> bool:
        """Whether the observation holds camera images (every mode but ``"state"``)."""
        return self.obs_mode != "state"


def apply_robot_overrides(robot: RobotOptions | None, overrides: Sequence[str]) -> RobotOptions:
    """``robot`` (default ``RobotOptions()``) with ``FIELD=VALUE`` overrides on top, e.g.
    ``("realism=fr3", "delay_ticks=0")`` (``impact-eval --robot-set``); a value is read as the
    field's type (``true``/``false`` for booleans, ``none`` for an optional field's None).
    One-line ``InvalidArgumentError`` naming the valid fields or values."""
    base = robot if robot is not None else RobotOptions()
    names = [f.name for f in fields(RobotOptions)]
    changes: dict[str, object] = {}
    for item in overrides:
        name, sep, text = str(item).partition("=")
        name = name.strip()
        if not sep or name not in names:
            raise InvalidArgumentError(
                f"invalid --robot-set {item!r}; valid: FIELD=VALUE with FIELD one of "
                f"{', '.join(names)}")
        changes[name] = _parse_field(name, text.strip())
    return replace(base, **changes)


ROBOT_CHOICES: dict[str, tuple[str, ...]] = {
    "hand": tuple(HANDS), "realism": REALISMS, "torque_reading": TORQUE_READINGS}
"""``RobotOptions`` fields whose value is one of a set of names."""


def _read_bool(text: str) -> bool:
    """``true`` or ``false`` (any case) as a bool; ValueError otherwise."""
    if text.lower() not in ("true", "false"):
        raise ValueError(text)
    return text.lower() == "true"


_READERS: dict[str, tuple[Callable[[str], object], str]] = {
    "bool": (_read_bool, "true or false"), "int": (int, "an integer"),
    "float": (float, "a number"), "str": (str, "a name")}
"""How ``--robot-set`` reads a value of each field type, and how its errors name the type."""


def robot_field_types() -> dict[str, tuple[str, bool]]:
    """Each ``RobotOptions`` field's type name (a key of ``_READERS``) and whether it may be
    None, from its annotation (e.g. ``"int | None"`` is ``("int", True)``)."""
    types = {}
    for f in fields(RobotOptions):
        parts = [part.strip() for part in str(f.type).split("|")]
        types[f.name] = (parts[0], "None" in parts)
    return types


def _parse_field(name: str, text: str) -> object:
    """``text`` as ``RobotOptions.name``'s value, read as the field's type (``none``: None
    where the field may be None); a one-line error naming that type or the valid choices."""
    kind, optional = robot_field_types()[name]
    if optional and text.lower() == "none":
        return None
    if name in ROBOT_CHOICES:
        check_choice(name, text, ROBOT_CHOICES[name] + (("none",) if optional else ()))
        return text
    read, valid = _READERS[kind]
    try:
        return read(text)
    except ValueError:
        or_none = " or none" if optional else ""
        raise InvalidArgumentError(
            f"invalid --robot-set {name}={text!r}; valid: {valid}{or_none}") from None
