"""Numba kernels of ``FrankaSim`` (sensing, actuation, state and contact checks).

Compiled once and cached (``impact_control.jit_cache`` keeps the cache in step); ``FrankaSim``
and the closed loop's tick (``impact_envs/loop``) call them on views of ``MjData``.
"""

from __future__ import annotations

import math

from numba import njit

GROUP_OTHER, GROUP_ROBOT, GROUP_OBJECT = 0, 1, 2
"""Contact classes of a geom (``FrankaSim`` classifies every geom once)."""


@njit(cache=True)
def link_torque(qfrc_actuator, qfrc_damper, frictionloss, out) -> None:
    """out = motor torque + joint damping + dof Coulomb friction (MuJoCo's ``frictionloss``):
    the link-side joint torque."""
    for j in range(out.shape[0]):
        out[j] = qfrc_actuator[j] + qfrc_damper[j] + frictionloss[j]


@njit(cache=True)
def sense(z, stds, qpos, qvel, qfrc_actuator, qfrc_damper, frictionloss, bias, out) -> None:
    """out = [q, dq, tau] readings: true values + stds[:3] * z (tau also + bias), z (3n,);
    q then rounded to a multiple of ``stds[3]`` [rad] when it is above 0 (encoder steps)."""
    n = qpos.shape[0]
    tau = out[2 * n:]
    link_torque(qfrc_actuator, qfrc_damper, frictionloss, tau)
    step = stds[3]
    for j in range(n):
        out[j] = qpos[j] + stds[0] * z[j]
        if step > 0.0:
            out[j] = step * math.floor(out[j] / step + 0.5)
        out[n + j] = qvel[j] + stds[1] * z[n + j]
        tau[j] = tau[j] + bias[j] + stds[2] * z[2 * n + j]


@njit(cache=True)
def actuate(tau, torque_limits, tau_applied, ctrl, arm_act, gripper_act, gripper_cmd) -> None:
    """tau_applied = clip(tau, +-limits) -> ctrl[arm_act]; ctrl[gripper] from cmd in [-1, 1].

    The drives enforce their own torque limits, whatever the controller sent (NaN passes to
    MuJoCo, whose state check then fails: nothing hides a non-finite command).
    """
    for j in range(arm_act.shape[0]):
        v = tau[j]
        if v > torque_limits[j]:
            v = torque_limits[j]
        if v < -torque_limits[j]:
            v = -torque_limits[j]
        tau_applied[j] = v
        ctrl[arm_act[j]] = v
    g = gripper_cmd
    if g > 1.0:
        g = 1.0
    if g < -1.0:
        g = -1.0
    ctrl[gripper_act] = 0.02 * (1.0 - g)


@njit(cache=True)
def send(tau, torque_limits, tau_applied, ctrl, arm_act, gripper_act, gripper_cmd,
         tau_pending, scratch, delay_ticks, lost) -> None:
    """``actuate`` as the robot receives the command: with ``delay_ticks`` = 1 the drives get
    the torque of the previous call (``tau`` waits in ``tau_pending``; ``scratch`` carries
    the one leaving it, ``tau`` itself is not written); a ``lost`` command leaves the arm's
    drives on the last torque they applied (the gripper, a device of its own, still gets its
    command)."""
    if lost:  # it never arrives: the queue keeps what it held
        actuate(tau_applied, torque_limits, tau_applied, ctrl, arm_act, gripper_act, gripper_cmd)
    elif delay_ticks > 0:
        for j in range(tau.shape[0]):
            scratch[j] = tau_pending[j]
            tau_pending[j] = tau[j]
        actuate(scratch, torque_limits, tau_applied, ctrl, arm_act, gripper_act, gripper_cmd)
    else:
        actuate(tau, torque_limits, tau_applied, ctrl, arm_act, gripper_act, gripper_cmd)


@njit(cache=True)
def state_status(qpos, qvel, max_speed) -> int:
    """0 when finite and |qvel| <= max_speed everywhere, 1 if not finite, 2 if too fast."""
    for v in qpos:
        if not math.isfinite(v):
            return 1
    for v in qvel:
        if not math.isfinite(v):
            return 1
    for v in qvel:
        if abs(v) > max_speed:
            return 2
    return 0


@njit(cache=True)
def count_body_contacts(ncon, geom, geom_bodyid, target, fingers) -> int:
    """Contacts between body ``target`` and any body in ``fingers``."""
    count = 0
    for i in range(ncon):
        b1, b2 = geom_bodyid[geom[i, 0]], geom_bodyid[geom[i, 1]]
        if b1 == target or b2 == target:
            for f in fingers:
                if b1 == f or b2 == f:
                    count += 1
                    break
    return count


@njit(cache=True)
def contact_sums(ncon, geom, efc_address, efc_force, geom_group):
    """Normal force sums (robot-environment, object-environment) over valid contacts."""
    robot_env = obj_env = 0.0
    for i in range(ncon):
        adr = efc_address[i]
        if adr < 0:
            continue
        g1, g2 = geom_group[geom[i, 0]], geom_group[geom[i, 1]]
        if (g1 == GROUP_ROBOT and g2 == GROUP_OTHER) or (g2 == GROUP_ROBOT and g1 == GROUP_OTHER):
            robot_env += efc_force[adr]
        elif (g1 == GROUP_OBJECT and g2 == GROUP_OTHER) or (
            g2 == GROUP_OBJECT and g1 == GROUP_OTHER
        ):
            obj_env += efc_force[adr]
    return robot_env, obj_env


@njit(cache=True)
def robot_contact_resultant(ncon, geom, efc_address, efc_force, frame, pos, geom_group,
                            geom_bodyid, out):
    """The environment's net normal force on the robot (``out[:3]`` [N, world]: the sum over
    robot-environment contacts of each normal force along its contact normal, which MuJoCo
    points from geom 1 to geom 2) and where it acts (``out[3:]``: the contacts' positions
    weighted by their normal forces [m]); returns the body id of the robot's geom in the
    hardest of them (-1 without robot-environment contact)."""
    for k in range(6):
        out[k] = 0.0
    total, hardest, body = 0.0, 0.0, -1
    for i in range(ncon):
        adr = efc_address[i]
        if adr < 0:
            continue
        g1, g2 = geom_group[geom[i, 0]], geom_group[geom[i, 1]]
        if g1 == GROUP_ROBOT and g2 == GROUP_OTHER:
            sign, robot_geom = -1.0, geom[i, 0]  # the robot is geom 1: pushed against n
        elif g2 == GROUP_ROBOT and g1 == GROUP_OTHER:
            sign, robot_geom = 1.0, geom[i, 1]
        else:
            continue
        f = efc_force[adr]
        for k in range(3):
            out[k] += sign * f * frame[i, k]
            out[3 + k] += f * pos[i, k]
        total += f
        if f > hardest:
            hardest, body = f, geom_bodyid[robot_geom]
    if total > 0.0:
        for k in range(3):
            out[3 + k] /= total
    return body
