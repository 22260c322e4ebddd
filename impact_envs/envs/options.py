"""Grouped constructor options of the IMPACT envs: the simulated robot and rendering."""

from __future__ import annotations

from dataclasses import dataclass

from impact_envs.errors import InvalidArgumentError


@dataclass(frozen=True)
class RobotOptions:
    """The simulated robot (``gym.make(id, robot=RobotOptions(...))``).

    Attributes:
        sensor_noise: Encoder and joint-torque noise on (docs/sensing.md) or all zero.
        grasp_force_n: Gripper squeeze force when closing on an object [N].
        model_mass_error: Relative error of the controller's link masses (0: exact model).
    """

    sensor_noise: bool = True
    grasp_force_n: float = 70.0
    model_mass_error: float = 0.0

    def __post_init__(self) -> None:
        if not self.grasp_force_n >= 0.0:
            raise InvalidArgumentError(
                f"invalid grasp_force_n {self.grasp_force_n!r}; valid: a force >= 0 N")
        if not -0.9 <= self.model_mass_error <= 10.0:
            raise InvalidArgumentError(
                f"invalid model_mass_error {self.model_mass_error!r}; valid: -0.9 to 10")


@dataclass(frozen=True)
class RenderOptions:
    """Offscreen rendering (``render_mode="rgb_array"``): image size [px] and camera name
    (``"overview"``, which frames the arm, the objects and the goal, ``"front"`` or ``"side"``;
    defined in assets/common.xml)."""

    width: int = 320
    height: int = 240
    camera: str = "overview"

    def __post_init__(self) -> None:
        if not (self.width >= 1 and self.height >= 1):
            raise InvalidArgumentError(
                f"invalid render size {self.width}x{self.height}; valid: positive pixels")
