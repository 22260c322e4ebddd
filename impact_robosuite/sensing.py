"""Proprioception of a robosuite arm as the FR3 gives it to IMPACT (emulated).

robosuite simulates no joint-torque sensor, so the reading is built as in our own simulator
(impact_envs/robot/sim_kernels.py, docs/sensing.md): the torque on the link side of each
joint's transmission, i.e. the actuator torque plus the joint's passive damping and its
dry-friction constraint force (both act before a link-side sensor), plus white noise and a
per-episode offset; encoders read position and velocity with white noise
(``impact_envs.robot.noise.SensorNoise``, the same defaults).

The friction term needs constraint forces of the current state. robosuite's default
``lite_physics`` steps with ``mj_step1`` / controller / ``mj_step2``, and between the two the
constraint rows are already the new state's while ``efc_force`` is still the last solve's
(other rows, other order: read as they are, they gave 2770 Nm on a joint). So the friction term
is added only when the env runs with ``lite_physics=False`` (``mj_forward`` before the
controller); with ``lite_physics`` the reading leaves it out, an error of at most the joints'
``frictionloss`` (0.1 Nm on robosuite's Panda arm joints, twice the torque noise).
"""

from __future__ import annotations

from typing import NamedTuple

import mujoco
import numpy as np

from impact_envs.robot.noise import SensorNoise


class Reading(NamedTuple):
    """One tick's sensed arm state: ``q`` [rad], ``dq`` [rad/s], link-side ``tau`` [Nm]."""

    q: np.ndarray
    dq: np.ndarray
    tau: np.ndarray


class ArmSensors:
    """Encoders and link-side joint-torque sensors on the given dofs of a MuJoCo model.

    Args:
        model: The simulation's MuJoCo model.
        qpos_index: ``qpos`` addresses of the arm joints.
        dof_index: ``qvel`` (dof) addresses of the arm joints.
        noise: Sensor noise (``SensorNoise.off()`` for exact readings).
        include_friction: Add the dof-friction constraint force (only when ``efc_force`` is
            current at read time; see the module docstring).
        seed: Seed of the noise stream (``reseed`` restarts it).
    """

    def __init__(self, model: mujoco.MjModel, qpos_index: np.ndarray, dof_index: np.ndarray,
                 noise: SensorNoise, include_friction: bool, seed: int = 0) -> None:
        self.model, self.noise, self.include_friction = model, noise, include_friction
        self.qpos_index, self.dof_index = np.asarray(qpos_index), np.asarray(dof_index)
        self._slot = np.full(model.nv, -1)
        self._slot[self.dof_index] = np.arange(len(self.dof_index))
        self.reseed(seed)

    def reseed(self, seed: int) -> None:
        """Restart the noise stream and draw a new torque-sensor offset."""
        self._rng = np.random.default_rng(seed)
        self._bias = self._rng.normal(0.0, self.noise.tau_bias_std_nm, len(self.dof_index))

    def friction(self, data: mujoco.MjData) -> np.ndarray:
        """Dry-friction constraint torque on the arm's dofs [Nm] (zero where none)."""
        out = np.zeros(len(self.dof_index))
        friction_rows = data.efc_type[:data.nefc] == mujoco.mjtConstraint.mjCNSTR_FRICTION_DOF
        rows = np.flatnonzero(friction_rows)
        slots = self._slot[data.efc_id[rows]]
        keep = slots >= 0
        np.add.at(out, slots[keep], data.efc_force[rows[keep]])
        return out

    def read(self, data: mujoco.MjData) -> Reading:
        """The readings at the current state of ``data``."""
        n, rng, s = len(self.dof_index), self._rng, self.noise
        tau = data.qfrc_actuator[self.dof_index] + data.qfrc_damper[self.dof_index]
        if self.include_friction:
            tau = tau + self.friction(data)
        return Reading(data.qpos[self.qpos_index] + rng.normal(0.0, s.q_std_rad, n),
                       data.qvel[self.dof_index] + rng.normal(0.0, s.dq_std_rad_s, n),
                       tau + self._bias + rng.normal(0.0, s.tau_std_nm, n))
