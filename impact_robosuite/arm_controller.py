"""``ImpactArmController``: our controller as a robosuite arm (part) controller.

Selected in robosuite's controller config as ``"type": "IMPACT"`` (the internal model's
feedforward on) or ``"IMPACT_IMPEDANCE"`` (the same task-space impedance, estimator and limits
without it: our baseline), after ``import impact_robosuite`` (``registry.py``).

Action: the 6-D delta pose of robosuite's default ``OSC_POSE`` (``[-1, 1]`` scaled to 5 cm and
0.5 rad, ``input_ref_frame`` "base"), so one policy drives OSC, impedance and IMPACT alike.
``goal_update_mode`` "achieved" (robosuite's default) adds the delta to the pose reached,
"desired" to the previous goal (kept within ``MAX_LEAD_M`` of the reached position). Each
physics step (robosuite's 500 Hz) reads the emulated
sensors (``sensing.py``), updates the MuJoCo-computed arm model (``MujocoArm``) and runs
``ImpactController.compute`` with ``dt_s`` set to the model's timestep; the torques come out
rate-limited and saturated at the FR3's (= Panda's) limits, gravity compensation included.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from robosuite.controllers.parts.controller import Controller
from scipy.spatial.transform import Rotation

from impact_control.config import ControllerConfig
from impact_control.controller import ImpactController
from impact_control.errors import InvalidArgumentError, check_choice
from impact_control.limits import LIBFRANKA_DELTA_T_S
from impact_control.presets import preset_config
from impact_envs.robot.mujoco_arm import MujocoArm
from impact_envs.robot.noise import SensorNoise
from impact_envs.torch_threads import limit_torch_threads
from impact_robosuite.sensing import ArmSensors

OUTPUT_MAX = (0.05, 0.05, 0.05, 0.5, 0.5, 0.5)
"""Largest goal change per policy step [m, rad] (robosuite's OSC_POSE default)."""
GOAL_UPDATE_MODES = ("achieved", "desired")
MAX_LEAD_M = 0.10
"""Farthest the position goal may lead the reached TCP position [m]: in "desired" mode a
closed-loop policy that keeps pushing against a load would otherwise wind the goal up without
bound (seen: 10 m away after a few seconds under a 4 kg cube)."""


@dataclass(frozen=True)
class ArmOptions:
    """Our settings of the arm controller: the keys of its robosuite config dict besides
    robosuite's own (``registry.py`` builds them from that dict).

    Attributes:
        mode: ``"impact"`` or ``"impedance"`` (from the config's ``type``).
        preset: Controller preset (``"default"`` or ``"paper"``, docs/controller.md).
        input_max, input_min: Action range (scalar or 6 values), as OSC's.
        output_max, output_min: Goal change per step at the action's range [m, rad], as OSC's.
        goal_update_mode: ``"achieved"`` or ``"desired"`` (see the module docstring).
        sensor_noise: Emulated encoder and torque-sensor noise on (``SensorNoise()``) or off.
        finger_joints: The gripper's finger joints; their opening is an internal-model feature.
    """

    mode: str = "impact"
    preset: str = "default"
    input_max: float | Sequence[float] = 1
    input_min: float | Sequence[float] = -1
    output_max: float | Sequence[float] = OUTPUT_MAX
    output_min: float | Sequence[float] = tuple(-v for v in OUTPUT_MAX)
    goal_update_mode: str = "achieved"
    sensor_noise: bool = True
    finger_joints: Sequence[str] = ("gripper0_right_finger_joint1",
                                    "gripper0_right_finger_joint2")

    def __post_init__(self) -> None:
        check_choice("goal_update_mode", self.goal_update_mode, GOAL_UPDATE_MODES)


class ImpactArmController(Controller):
    """IMPACT or impedance on a robosuite arm.

    Args:
        sim, ref_name, joint_indexes, actuator_range, part_name, naming_prefix, lite_physics:
            what robosuite gives every arm controller.
        options: Ours (``ArmOptions``; default: IMPACT, ``default`` preset, OSC's scaling).
    """

    def __init__(self, sim, ref_name, joint_indexes, actuator_range,
                 options: ArmOptions | None = None, part_name=None, naming_prefix=None,
                 lite_physics=True) -> None:
        options = options or ArmOptions()
        super().__init__(sim, joint_indexes, actuator_range, ref_name=ref_name,
                         part_name=part_name, naming_prefix=naming_prefix,
                         lite_physics=lite_physics)
        model = sim.model._model
        self.control_dim = 6
        self.input_max = self.nums2array(options.input_max, 6)
        self.input_min = self.nums2array(options.input_min, 6)
        self.output_max = self.nums2array(options.output_max, 6)
        self.output_min = self.nums2array(options.output_min, 6)
        self.goal_update_mode = options.goal_update_mode
        config = preset_at_timestep(options.preset, float(model.opt.timestep))
        self.arm_model = MujocoArm(model, self.joint_names, ref_name, sim.data.qpos.copy())
        limit_torch_threads()
        self.core = ImpactController(self.arm_model, config, options.mode)
        noise = SensorNoise() if options.sensor_noise else SensorNoise.off()
        self.sensors = ArmSensors(model, self.qpos_index, self.qvel_index, noise,
                                   include_friction=not lite_physics)
        try:
            self._fingers = [model.joint(name).qposadr[0] for name in options.finger_joints]
        except KeyError:
            raise InvalidArgumentError(f"finger joints {list(options.finger_joints)} not in the "
                                       "model; "
                                       "give the gripper's finger_joints") from None
        self.goal_pos, self.goal_ori = None, None
        self.reset_goal()

    @property
    def name(self) -> str:
        return "IMPACT" if self.core.mode == "impact" else "IMPACT_IMPEDANCE"

    def _base_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """The controller frame (robosuite's part ``_center`` site), identity before it is set."""
        if self.origin_pos is None:
            return np.zeros(3), np.eye(3)
        return np.asarray(self.origin_pos), np.asarray(self.origin_ori)

    def reset_goal(self) -> None:
        """Goal := the current TCP pose (base frame); a new episode for the controller (its
        internal model starts untrained, as in the IMPACT envs)."""
        self.update(force=True)
        pos, rot = self._base_pose()
        self.goal_pos = rot.T @ (self.ref_pos - pos)
        self.goal_ori = rot.T @ self.ref_ori_mat
        self.core.reset(np.array(self.joint_pos))

    def set_goal(self, action) -> None:
        """Add the scaled delta (base frame) to the achieved or the desired pose."""
        self.update()
        delta = self.scale_action(np.asarray(action, float))
        pos, rot = self._base_pose()
        if self.goal_update_mode == "achieved":
            self.goal_pos = rot.T @ (self.ref_pos - pos)
            self.goal_ori = rot.T @ self.ref_ori_mat
        achieved = rot.T @ (self.ref_pos - pos)
        lead = self.goal_pos + delta[:3] - achieved  # bounded: no wind-up of a "desired" goal
        self.goal_pos = achieved + lead * min(1.0, MAX_LEAD_M / max(float(np.linalg.norm(lead)),
                                                                    1e-12))
        self.goal_ori = Rotation.from_rotvec(delta[3:]).as_matrix() @ self.goal_ori

    def run_controller(self) -> np.ndarray:
        """Joint torques for this physics step [Nm]."""
        self.update()
        pos, rot = self._base_pose()
        target_pos = pos + rot @ self.goal_pos
        x, y, z, w = Rotation.from_matrix(rot @ self.goal_ori).as_quat()
        reading = self.sensors.read(self.sim.data._data)
        width = float(sum(abs(self.sim.data.qpos[i]) for i in self._fingers))
        self.torques = self.core.compute(reading.q, reading.dq, reading.tau, target_pos,
                                         np.array([w, x, y, z]), gripper_width_m=width)
        super().run_controller()
        return self.torques


def preset_at_timestep(preset: str, dt_s: float) -> ControllerConfig:
    """Preset ``preset`` at controller period ``dt_s`` [s]: libfranka's rate limiter needs
    1 ms, so another period limits the torque rate per tick (``rate_limiter="per_tick_clip"``,
    the same 999.999 Nm/s)."""
    config = preset_config(preset)
    if dt_s != LIBFRANKA_DELTA_T_S:
        config = dataclasses.replace(
            config, limits=dataclasses.replace(config.limits, rate_limiter="per_tick_clip"))
    return dataclasses.replace(config, dt_s=dt_s)
