"""The simulated sensors' noise model (docs/sensing.md)."""

from __future__ import annotations

from dataclasses import dataclass

from impact_control.errors import InvalidArgumentError


@dataclass(frozen=True)
class SensorNoise:
    """Noise of the simulated proprioception (docs/sensing.md gives the sources).

    Attributes:
        q_std_rad: white noise on joint positions [rad].
        dq_std_rad_s: white noise on joint velocities [rad/s].
        tau_std_nm: white noise on the joint-torque sensors [Nm].
        tau_bias_std_nm: std of a per-episode constant torque-sensor offset [Nm].
        q_step_rad: quantization step of the joint-position reading [rad] (0: none),
            applied after the noise.
    """

    q_std_rad: float = 1e-5
    dq_std_rad_s: float = 1e-3
    tau_std_nm: float = 0.05
    tau_bias_std_nm: float = 0.02
    q_step_rad: float = 0.0

    def __post_init__(self) -> None:
        for name in ("q_std_rad", "dq_std_rad_s", "tau_std_nm", "tau_bias_std_nm", "q_step_rad"):
            if not getattr(self, name) >= 0.0:
                raise InvalidArgumentError(f"SensorNoise.{name} must be >= 0")

    @classmethod
    def off(cls) -> SensorNoise:
        """Noise-free sensing."""
        return cls(0.0, 0.0, 0.0, 0.0, 0.0)
