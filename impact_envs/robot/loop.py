"""One 1 kHz tick of the closed loop: sense (with noise) -> control -> actuate -> step physics.

Shared by the Gymnasium envs and the physics experiments so that both run identical code.
"""

from __future__ import annotations

import numpy as np

from impact_envs.control.controller import ImpactController
from impact_envs.robot.sim import FrankaSim


def control_tick(
    sim: FrankaSim,
    controller: ImpactController,
    rng: np.random.Generator,
    pos_target_world: np.ndarray,
    quat_target_world: np.ndarray,
    gripper_cmd: float,
    wrench_cmd_world: np.ndarray | None = None,
    learn_mask: np.ndarray | None = None,
    noise: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Run one control tick; return the sensed ``(q, dq)`` the controller used.

    ``noise``: optional (21,) standard-normal draws for the sensor reading instead of drawing
    them from ``rng`` (see ``FrankaSim.read_sensors``).
    """
    q, dq, tau_meas = sim.read_sensors(rng, noise)
    tau = controller.compute(q, dq, tau_meas, pos_target_world, quat_target_world,
                             wrench_cmd_world=wrench_cmd_world, learn_mask=learn_mask,
                             gripper_width_m=sim.gripper_width())
    sim.apply(tau, gripper_cmd)
    sim.step()
    return q, dq
