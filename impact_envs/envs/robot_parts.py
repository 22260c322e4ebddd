"""The simulated robot and the controller's model of it, built from ``RobotOptions``: what
the envs and the experiments that build their own robot (physics checks, press, rest
offsets) share, so a robot profile means the same everywhere."""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

from impact_control.dynamics import ModelPerturbation, PinocchioArm
from impact_envs.envs.options import RobotOptions
from impact_envs.robot.noise import SensorNoise
from impact_envs.robot.realism import Realism
from impact_envs.robot.sim import FrankaSim


class RobotParts(NamedTuple):
    """``sim`` (the plant, its sensors and drives), ``dynamics`` (the controller's model,
    with the profile's errors) and ``realism`` (the resolved profile)."""

    sim: FrankaSim
    dynamics: PinocchioArm
    realism: Realism


def realism_noise(sensor_noise: bool, realism: Realism) -> SensorNoise:
    """The sensors' noise under ``realism``: ``SensorNoise``'s white noise with the profile's
    torque offsets and encoder steps; all off without ``sensor_noise``."""
    if not sensor_noise:
        return SensorNoise.off()
    return SensorNoise(tau_bias_std_nm=realism.tau_offset_std_nm,
                       q_step_rad=realism.encoder_step_rad)


def build_robot(robot: RobotOptions, scene_xml: str | Path, object_bodies: tuple[str, ...] = (),
                task_hand: str = "franka_hand") -> RobotParts:
    """The simulator of ``scene_xml`` and the controller's arm model, as ``robot`` says
    (its hand and grasp force against ``task_hand``'s, its torque reading and profile)."""
    realism = robot.resolved_realism()
    hand, grasp_force_n = robot.grasp(task_hand)
    drift = realism.tau_offset_drift_nm_per_sqrt_s if robot.sensor_noise else 0.0
    sim = FrankaSim(scene_xml, object_bodies, grasp_force_n=grasp_force_n, hand=hand,
                    noise=realism_noise(robot.sensor_noise, realism),
                    torque_reading=robot.torque_reading, delay_ticks=realism.delay_ticks,
                    offset_drift_nm_per_sqrt_s=drift)
    perturbation = ModelPerturbation(
        link_mass_scale=1.0 + float(robot.model_mass_error),
        link_mass_noise=realism.model_link_mass_std, com_noise_m=realism.model_com_std_m,
        inertia_noise=realism.model_inertia_std, seed=realism.model_seed)
    return RobotParts(sim, PinocchioArm(perturbation=perturbation), realism)
