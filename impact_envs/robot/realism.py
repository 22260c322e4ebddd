"""Named robot profiles: how far the simulated FR3 departs from an ideal one (docs/sensing.md,
"Realism profiles", gives every value's source).

``"ideal"`` is the simulated robot every result up to issue 39 was made with: the exact
dynamics model, state and command in the same tick, small torque-sensor offsets.
``"fr3"`` is a robot as imperfect as a real FR3: an averaged dynamics model, torque-sensor
offsets that drift, a one-tick delay and quantized encoders. ``RobotOptions`` resolves a
profile with its explicit fields on top (``Realism.resolve``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

from impact_control.errors import InvalidArgumentError

REALISMS = ("ideal", "fr3")
"""The named profiles."""


@dataclass(frozen=True)
class Realism:
    """The imperfections of the simulated robot, resolved from a profile.

    Attributes:
        tau_offset_std_nm: std of each joint-torque sensor's per-episode offset [Nm] (drawn
            at reset, constant over the episode but for the drift). Off with
            ``sensor_noise=False``.
        tau_offset_drift_nm_per_sqrt_s: random-walk intensity of the offsets [Nm/sqrt(s)]:
            over ``t`` seconds an offset wanders by this times sqrt(t) (std), updated once per
            policy step. Off with ``sensor_noise=False``.
        model_link_mass_std: std of the relative error of each link's mass in the
            controller's model [-] (the simulator is unchanged; a fixed robot, see
            ``model_seed``).
        model_com_std_m: std of each link's centre-of-mass error in the controller's model,
            per axis of the link frame [m].
        model_inertia_std: std of the relative error of each link's rotational inertia in the
            controller's model [-].
        model_seed: which robot: the seed of the model's per-link errors (one robot keeps its
            model errors across episodes, as a real arm keeps its averaged model).
        delay_ticks: ticks between the state the controller reads and the tick its torque
            is applied (0 or 1).
        command_loss_rate: probability that a tick's command is lost [-]; the robot then
            repeats the last command it applied.
        encoder_step_rad: quantization step of the joint-position reading [rad] (0: none).
            Off with ``sensor_noise=False``.
    """

    tau_offset_std_nm: float = 0.02
    tau_offset_drift_nm_per_sqrt_s: float = 0.0
    model_link_mass_std: float = 0.0
    model_com_std_m: float = 0.0
    model_inertia_std: float = 0.0
    model_seed: int = 0
    delay_ticks: int = 0
    command_loss_rate: float = 0.0
    encoder_step_rad: float = 0.0

    def __post_init__(self) -> None:
        limits = {"tau_offset_std_nm": (0.0, 5.0, " Nm"),
                  "tau_offset_drift_nm_per_sqrt_s": (0.0, 1.0, " Nm/sqrt(s)"),
                  "model_link_mass_std": (0.0, 0.3, ""), "model_com_std_m": (0.0, 0.05, " m"),
                  "model_inertia_std": (0.0, 0.3, ""), "command_loss_rate": (0.0, 0.5, ""),
                  "encoder_step_rad": (0.0, 1e-2, " rad")}
        for name, (low, high, unit) in limits.items():
            _check_real(name, getattr(self, name), low, high, unit)
        for name, high in (("model_seed", 2**32 - 1), ("delay_ticks", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= high:
                raise InvalidArgumentError(
                    f"invalid {name} {value!r}; valid: an integer from 0 to {high}")

    @property
    def perturbs_model(self) -> bool:
        """Whether the controller's model differs from the plant link by link."""
        return bool(self.model_link_mass_std or self.model_com_std_m or self.model_inertia_std)

    @classmethod
    def resolve(cls, profile: str, **overrides: object) -> Realism:
        """``profile``'s values with every override that is not None on top (one-line error
        naming the valid choices for an unknown profile or field)."""
        if profile not in PROFILES:
            raise InvalidArgumentError(
                f"invalid realism {profile!r}; valid choices: {', '.join(REALISMS)}")
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(overrides) - names)
        if unknown:
            raise InvalidArgumentError(f"invalid realism field {unknown[0]!r}; valid: "
                                       f"{', '.join(sorted(names))}")
        return replace(PROFILES[profile], **{k: v for k, v in overrides.items() if v is not None})


def _check_real(name: str, value: object, low: float, high: float, unit: str) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
            math.isfinite(float(value)) and low <= float(value) <= high):
        raise InvalidArgumentError(f"invalid {name} {value!r}; valid: a number from {low:g} to "
                                   f"{high:g}{unit}")


ENCODER_STEP_FR3_RAD = 2.0 * math.pi / 2**19
"""≈1.2e-5 rad: a 19-bit absolute encoder per revolution, the order of the 1e-5 rad position
resolution docs/sensing.md uses for the FR3's link-side encoders (no published FR3 figure)."""

PROFILES: dict[str, Realism] = {
    "ideal": Realism(),
    "fr3": Realism(tau_offset_std_nm=0.2, tau_offset_drift_nm_per_sqrt_s=0.01,
                   model_link_mass_std=0.05, model_com_std_m=0.005, model_inertia_std=0.10,
                   delay_ticks=1, command_loss_rate=0.0, encoder_step_rad=ENCODER_STEP_FR3_RAD),
}
"""The profiles' values; docs/sensing.md, "Realism profiles", gives each one's source."""
