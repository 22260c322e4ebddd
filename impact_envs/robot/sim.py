"""MuJoCo side of the robot: a thin adapter that looks names up once.

It reads the simulated sensors (encoders and joint-torque sensors, with configurable noise),
applies joint torques and the gripper command, and classifies contacts for safety metrics.
Everything a real FR3 would not provide (true contact forces, object poses) is exposed under
names that say so; the controller never sees it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import mujoco
import numpy as np

from impact_control.dynamics import ARM_JOINTS, FINGER_JOINTS
from impact_control.errors import InvalidArgumentError, SimulationError
from impact_envs.robot.hand import check_grasp_force, check_hand
from impact_envs.robot.noise import SensorNoise
from impact_envs.robot.scene import load_scene
from impact_envs.robot.sim_kernels import (
    GROUP_OBJECT,
    GROUP_OTHER,
    GROUP_ROBOT,
    contact_sums,
    count_body_contacts,
    link_torque,
    robot_contact_resultant,
    send,
    sense,
    state_status,
)

TORQUE_READINGS = ("link_side", "commanded")
"""What the controller reads as the measured joint torque (``FrankaSim(torque_reading=...)``,
``RobotOptions.torque_reading``; docs/sensing.md): ``"link_side"`` the FR3's link-side
joint-torque sensors (motor torque + joint damping + dof Coulomb friction, with bias and
noise; the default); ``"commanded"`` the torque the drives applied (MuJoCo ``qfrc_actuator``
of the arm), without torque noise or bias, as in the paper authors' simulation."""


def check_torque_reading(value: object) -> None:
    """One-line ``InvalidArgumentError`` unless ``value`` is one of ``TORQUE_READINGS``."""
    if not isinstance(value, str) or value not in TORQUE_READINGS:
        raise InvalidArgumentError(
            f"invalid torque_reading {value!r}; valid choices: {', '.join(TORQUE_READINGS)}")


class SimArrays(NamedTuple):
    """What the closed loop's per-tick kernel reads and writes in the simulator.

    ``noise_stds`` = [q, dq, tau] sensor noise [rad, rad/s, Nm] and the encoder step [rad]
    (0: none); the arm's ``qpos``,
    ``qvel``, ``qfrc_actuator`` and ``qfrc_damper`` as views of ``MjData`` (with
    ``torque_reading="commanded"`` the damper is a zero array, and the tau noise and the
    bias are zero); ``tau_bias`` the episode's torque-sensor bias [Nm]; ``qpos`` all of it
    (fingers at ``finger_i``/``_j``); ``torque_limits`` the hardware limits [Nm];
    ``tau_applied`` the last torque sent [Nm]; ``ctrl`` MuJoCo's controls, with the arm's
    actuators at ``arm_act`` and the gripper's at ``gripper_act``; ``tau_pending`` the
    command waiting for the next tick when ``delay_ticks`` is 1, ``tau_scratch`` a work array
    (``sim_kernels.send``).
    """

    noise_stds: np.ndarray
    qpos_arm: np.ndarray
    qvel_arm: np.ndarray
    qfrc_actuator_arm: np.ndarray
    qfrc_damper_arm: np.ndarray
    tau_bias: np.ndarray
    qpos: np.ndarray
    finger_i: int
    finger_j: int
    torque_limits: np.ndarray
    tau_applied: np.ndarray
    ctrl: np.ndarray
    arm_act: np.ndarray
    gripper_act: int
    tau_pending: np.ndarray
    tau_scratch: np.ndarray
    delay_ticks: int



def _as_slice(indices: list[int]) -> slice | np.ndarray:
    """A slice for contiguous ascending indices (cheaper to index with), else an index array."""
    idx = np.asarray(indices, dtype=int)
    if np.array_equal(idx, np.arange(idx[0], idx[0] + idx.size)):
        return slice(int(idx[0]), int(idx[0]) + idx.size)
    return idx


def contact_force_world(model: mujoco.MjModel, data: mujoco.MjData, i: int) -> np.ndarray:
    """Contact ``i``'s full force (normal and friction, ``mujoco.mj_contactForce``) on its
    geom 2, in world axes [N] (3,); the force on geom 1 is its negative (MuJoCo's normal
    points from geom 1 to geom 2)."""
    force = np.zeros(6)
    mujoco.mj_contactForce(model, data, i, force)  # in the contact frame
    return data.contact.frame[i].reshape(3, 3).T @ force[:3]


class FrankaSim:
    """A MuJoCo scene that contains the FR3 + Hand (``fr3_hand.xml``) and task objects.

    Args:
        scene_xml: scene file (absolute, or a file name inside ``impact_envs/assets``).
        object_bodies: names of the task's movable bodies (grouped as "object" for contacts).
        grasp_force_n: gripper squeeze force when closing on an object [N], at most the
            hand's largest (``robot/hand.py``).
        hand: which hand's grasp-force range applies, one of ``hand.HANDS``.
        noise: sensor noise model.
        torque_reading: one of ``TORQUE_READINGS``: the link-side torque sensors
            (``"link_side"``) or the applied torque, noise- and bias-free (``"commanded"``);
            encoder noise is the same in both.
        delay_ticks: 0, or 1: a command reaches the drives one tick after it is sent
            (``robot/realism.py``).
        offset_drift_nm_per_sqrt_s: random-walk intensity of the torque-sensor offsets
            [Nm/sqrt(s)] (``drift_offsets``; none in a ``"commanded"`` reading).
    """

    def __init__(
        self,
        scene_xml: str | Path,
        object_bodies: tuple[str, ...] = (),
        *,
        grasp_force_n: float = 70.0,
        hand: str = "franka_hand",
        noise: SensorNoise | None = None,
        torque_reading: str = "link_side",
        delay_ticks: int = 0,
        offset_drift_nm_per_sqrt_s: float = 0.0,
    ) -> None:
        check_torque_reading(torque_reading)
        self.delay_ticks = int(delay_ticks)
        self.offset_drift_nm_per_sqrt_s = float(offset_drift_nm_per_sqrt_s)
        self._commanded = torque_reading == "commanded"
        self._zero_torque = np.zeros(7)
        """Stands in for damping, friction (and bias) in a ``"commanded"`` reading."""
        self.model = load_scene(scene_xml)
        self.data = mujoco.MjData(self.model)
        self.noise = noise or SensorNoise()
        m = self.model
        self.dt = float(m.opt.timestep)
        self.arm_qpos = _as_slice([m.jnt_qposadr[m.joint(n).id] for n in ARM_JOINTS])
        self.arm_dof = _as_slice([m.jnt_dofadr[m.joint(n).id] for n in ARM_JOINTS])
        self.finger_qpos = np.array([m.jnt_qposadr[m.joint(n).id] for n in FINGER_JOINTS])
        self.arm_act = np.array([m.actuator(f"tau{i}").id for i in range(1, 8)])
        self.gripper_act = m.actuator("gripper").id
        self.tcp_site = m.site("tcp").id
        self.torque_limits = m.actuator_ctrlrange[self.arm_act, 1].copy()
        self.hand = check_hand(hand)
        self.set_grasp_force(grasp_force_n)
        self.geom_group = self._classify_geoms(object_bodies)
        self._tau_bias = np.zeros(7)
        self.tau_applied = np.zeros(7)
        self.tau_pending = np.zeros(7)
        self._tau_scratch = np.zeros(7)
        self._resultant = np.zeros(6)  # push_into_contact's scratch
        self._jac_scratch = tuple(np.zeros((3, m.nv)) for _ in range(3))
        self._init_fast_paths()


    def state_arrays(self) -> dict[str, np.ndarray]:
        """The arrays besides ``model`` / ``data`` that carry the simulation from one step to
        the next, by name, live (``ImpactEnv.get_state`` copies them)."""
        arrays = {"tau_bias": self._tau_bias, "tau_applied": self.tau_applied}
        if self.delay_ticks:  # ideal robots keep their saved states' names
            arrays["tau_pending"] = self.tau_pending
        return arrays

    def _init_fast_paths(self) -> None:
        """Buffers and ids of the per-tick helpers (friction rows, fingers, bound views)."""
        m = self.model
        self._fric_type = int(mujoco.mjtConstraint.mjCNSTR_FRICTION_DOF)
        self._fric_buffer = np.zeros(m.nv)
        self._fric_arm = np.zeros(7)
        self._fric_rows_are_arm: bool | None = None
        self._finger_ids = tuple(int(i) for i in self.finger_qpos)
        names = ("left_finger", "right_finger")
        self._finger_bodies = np.array(
            [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, n) for n in names], dtype=np.int64
        )
        self._bound_data: mujoco.MjData | None = None

    @property
    def noise(self) -> SensorNoise:
        """Sensor noise model (assignable)."""
        return self._noise

    @noise.setter
    def noise(self, value: SensorNoise) -> None:
        self._noise = value
        tau_std = 0.0 if self._commanded else value.tau_std_nm
        self._noise_stds = np.array([value.q_std_rad, value.dq_std_rad_s, tau_std,
                                     value.q_step_rad])

    @property
    def torque_reading(self) -> str:
        """What ``read_sensors`` and the loop read as joint torque (``TORQUE_READINGS``)."""
        return "commanded" if self._commanded else "link_side"

    def _arm_views(self) -> tuple[np.ndarray, ...]:
        """(qpos, qvel, qfrc_actuator, qfrc_damper) of the arm, as views when contiguous.

        MuJoCo allocates these arrays once per MjData, so the views (and full ``qpos`` / ``ctrl``
        views for the gripper and actuation) are made once, again if ``data`` is replaced;
        index arrays fall back to copies.
        """
        d = self.data
        if d is not self._bound_data:
            self._views = (d.qpos[self.arm_qpos], d.qvel[self.arm_dof],
                           d.qfrc_actuator[self.arm_dof], d.qfrc_damper[self.arm_dof])
            self._qpos, self._ctrl = d.qpos, d.ctrl
            self._bound_data = d
        if isinstance(self.arm_qpos, slice) and isinstance(self.arm_dof, slice):
            return self._views
        return (d.qpos[self.arm_qpos], d.qvel[self.arm_dof], d.qfrc_actuator[self.arm_dof],
                d.qfrc_damper[self.arm_dof])

    def _classify_geoms(self, object_bodies: tuple[str, ...]) -> np.ndarray:
        m = self.model
        root = m.body("fr3_link0").id
        objects = {m.body(n).id for n in object_bodies}
        group = np.full(m.ngeom, GROUP_OTHER, dtype=np.int8)
        for g in range(m.ngeom):
            body = int(m.geom_bodyid[g])
            if body in objects or int(m.body_rootid[body]) in objects:
                group[g] = GROUP_OBJECT
            elif int(m.body_rootid[body]) == int(m.body_rootid[root]) and body != 0:
                group[g] = GROUP_ROBOT
        return group

    def set_grasp_force(self, force_n: float) -> None:
        """Set the gripper squeeze force [N] (the tendon carries each finger at coef 0.5)."""
        check_grasp_force(force_n, self.hand)
        self.model.actuator_forcerange[self.gripper_act] = (-2.0 * force_n, 2.0 * force_n)

    # ----------------------------------------------------------------- state
    def reset_robot(self, q: np.ndarray, finger_opening_m: float, rng: np.random.Generator) -> None:
        """Place the arm at rest at ``q`` with the fingers at ``finger_opening_m`` each."""
        d = self.data
        d.qpos[self.arm_qpos] = q
        d.qvel[self.arm_dof] = 0.0
        d.qpos[self.finger_qpos] = finger_opening_m
        d.ctrl[:] = 0.0
        d.ctrl[self.gripper_act] = finger_opening_m
        self.tau_applied[:] = 0.0
        self.tau_pending[:] = 0.0
        bias_std = 0.0 if self._commanded else self.noise.tau_bias_std_nm
        self._tau_bias[:] = bias_std * rng.standard_normal(7)  # drawn in both readings

    def drift_offsets(self, dt_s: float, rng: np.random.Generator) -> None:
        """Let the torque-sensor offsets wander for ``dt_s`` seconds: each joint's offset
        gets ``offset_drift_nm_per_sqrt_s * sqrt(dt_s) * N(0, 1)`` [Nm] (nothing drawn when
        the intensity is 0 or the reading is ``"commanded"``)."""
        if self.offset_drift_nm_per_sqrt_s > 0.0 and not self._commanded:
            self._tau_bias += (self.offset_drift_nm_per_sqrt_s * math.sqrt(dt_s)
                               * rng.standard_normal(7))

    def arm_state(self) -> tuple[np.ndarray, np.ndarray]:
        """True joint positions [rad] and velocities [rad/s] (privileged)."""
        return self.data.qpos[self.arm_qpos].copy(), self.data.qvel[self.arm_dof].copy()

    def read_sensors(
        self, rng: np.random.Generator, noise: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Encoder and joint-torque sensor readings with noise: ``(q, dq, tau_measured)``.

        The torque sensor sits on the link side of each joint's transmission: it reads the motor
        torque minus joint damping and Coulomb friction, so the rigid-body equation
        ``M(q) q'' + C q' + g = tau_measured + tau_ext`` holds with the armature in M. With
        ``torque_reading="commanded"`` tau is the applied torque (``qfrc_actuator``) exactly,
        and damping and friction join ``tau_ext``. The three arrays are views of one new (21,)
        array.

        Args:
            rng: Source of the 21 standard-normal draws of this reading.
            noise: Optional (21,) draws to use instead of drawing from ``rng`` (the env draws
                all readings of a policy step at once: the same numbers, one call).
        """
        z = rng.standard_normal(21) if noise is None else noise
        out = np.empty(21)
        qpos, qvel, qfrc_actuator, damper = self._sensed_views()
        sense(z, self._noise_stds, qpos, qvel, qfrc_actuator, damper, self.frictionloss_reader()(),
              self._tau_bias, out)
        return out[:7], out[7:14], out[14:]

    def _sensed_views(self) -> tuple[np.ndarray, ...]:
        """``_arm_views`` as the torque reading sees them: the damper's view replaced by zeros
        in a ``"commanded"`` reading."""
        views = self._arm_views()
        if self._commanded:
            return (*views[:3], self._zero_torque)
        return views

    def frictionloss_reader(self) -> Callable[[], np.ndarray]:
        """The function that gives the Coulomb friction inside the torque reading [Nm], called
        before each tick (the closed loop passes its result to ``loop_tick``):
        ``frictionloss_torque`` for ``"link_side"``, zeros for ``"commanded"``."""
        return self._no_friction if self._commanded else self.frictionloss_torque

    def _no_friction(self) -> np.ndarray:
        """Zeros [Nm]: a ``"commanded"`` reading has no friction term."""
        return self._zero_torque

    def loop_arrays(self) -> SimArrays:
        """Sensing and actuation arrays of the closed loop's tick (views of ``MjData``, valid
        until ``data`` is replaced).

        Raises:
            InvalidArgumentError: The arm's joints are not contiguous in MuJoCo's arrays
                (the per-tick kernel reads them as views).
        """
        if not (isinstance(self.arm_qpos, slice) and isinstance(self.arm_dof, slice)):
            raise InvalidArgumentError(
                "the arm's qpos/qvel are not contiguous in this scene; valid: the seven arm "
                "joints declared one after another (as in impact_control/assets/fr3_hand.xml)")
        qpos_arm, qvel_arm, qfrc_actuator, qfrc_damper = self._sensed_views()
        finger_i, finger_j = self._finger_ids
        return SimArrays(self._noise_stds, qpos_arm, qvel_arm, qfrc_actuator, qfrc_damper,
                         self._tau_bias, self._qpos, finger_i, finger_j, self.torque_limits,
                         self.tau_applied, self._ctrl, self.arm_act, int(self.gripper_act),
                         self.tau_pending, self._tau_scratch, self.delay_ticks)

    def true_joint_torque(self) -> np.ndarray:
        """Noise-free link-side joint torque of the last step [Nm] (a new array).

        Motor torque + joint damping + the dof Coulomb-friction constraint force.
        """
        tau = np.empty(7)
        qpos, qvel, qfrc_actuator, qfrc_damper = self._arm_views()
        link_torque(qfrc_actuator, qfrc_damper, self.frictionloss_torque(), tau)
        return tau

    def frictionloss_torque(self) -> np.ndarray:
        """Dof Coulomb-friction constraint force on the arm joints [Nm] (zeros if none).

        MuJoCo orders constraint rows equality first, then dof friction (``nf`` rows, in dof
        order); when the first seven rows are the arm's, they are returned as a view.
        """
        d = self.data
        nf = d.nf
        if not nf:
            self._fric_arm.fill(0.0)
            return self._fric_arm
        start = d.ne
        dof = self.arm_dof
        if self._fric_rows_are_arm is None:
            ids = d.efc_id[start:start + nf]
            self._fric_rows_are_arm = (
                isinstance(dof, slice) and ids.size >= 7
                and np.array_equal(ids[:7], np.arange(dof.start, dof.stop)))
        if self._fric_rows_are_arm:
            return d.efc_force[start:start + 7]
        fric = self._fric_buffer
        fric.fill(0.0)
        fric[d.efc_id[start:start + nf]] = d.efc_force[start:start + nf]
        self._fric_arm[:] = fric[dof]
        return self._fric_arm

    def gripper_width(self) -> float:
        """Distance between the finger pads [m] (encoder of the hand)."""
        self._arm_views()
        qpos = self._qpos
        i, j = self._finger_ids
        return float(qpos[i] + qpos[j])

    def tcp_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """True TCP position [m] and rotation matrix in the world frame."""
        d = self.data
        return d.site_xpos[self.tcp_site].copy(), d.site_xmat[self.tcp_site].reshape(3, 3).copy()

    # --------------------------------------------------------------- actuation
    def apply(self, tau: np.ndarray, gripper_cmd: float) -> None:
        """Send joint torques [Nm] (saturated at the FR3 limits) and the gripper command;
        with ``delay_ticks`` = 1 the drives get the torque sent one call before.

        ``gripper_cmd`` in [-1, 1]: -1 fully open (0.08 m), +1 closed (force-limited squeeze).
        """
        self._arm_views()
        send(np.asarray(tau, dtype=np.float64), self.torque_limits, self.tau_applied,
             self._ctrl, self.arm_act, self.gripper_act, float(gripper_cmd), self.tau_pending,
             self._tau_scratch, self.delay_ticks, False)

    def step(self) -> None:
        """Advance the physics by one control tick (``dt``)."""
        mujoco.mj_step(self.model, self.data)

    def check_finite(self) -> None:
        """Raise SimulationError when the state diverged."""
        d = self.data
        status = state_status(d.qpos, d.qvel, 100.0)
        if status == 1:
            raise SimulationError(f"non-finite state at t={d.time:.3f} s")
        if status == 2:
            raise SimulationError(f"velocity blow-up at t={d.time:.3f} s")

    # ---------------------------------------------------------------- contacts
    def contact_forces(self) -> tuple[float, float]:
        """Total normal contact force [N] robot-vs-environment and object-vs-environment.

        "Environment" is everything that is neither robot nor task object (table, basket, pads).
        Finger-object contacts (the grasp) are excluded. Uses the first (normal) row of each
        contact in the elliptic-cone constraint layout.
        """
        d = self.data
        ncon = d.ncon
        if ncon == 0:
            return 0.0, 0.0
        con = d.contact
        return contact_sums(ncon, con.geom, con.efc_address, d.efc_force, self.geom_group)

    def object_net_contact(self) -> float:
        """Magnitude [N] of the **net** force the environment exerts on the task objects:
        each object-environment contact's full force (normal and friction,
        ``mujoco.mj_contactForce``) in world axes, summed as vectors. A hammer resting in the
        basket gives its weight however its contacts are loaded; a body wedged between a floor
        and a wall, whose normals cancel against its friction, gives its weight too, where
        ``contact_forces`` sums kilonewtons of normals (docs/hammer_basket.md, "Contact after
        a success"). Finger-object contacts are excluded (the grasp)."""
        d, group = self.data, self.geom_group
        net = np.zeros(3)
        for i in range(d.ncon):
            g1, g2 = group[d.contact.geom[i, 0]], group[d.contact.geom[i, 1]]
            if {g1, g2} != {GROUP_OBJECT, GROUP_OTHER} or d.contact.efc_address[i] < 0:
                continue
            world = contact_force_world(self.model, d, i)
            net += world if g2 == GROUP_OBJECT else -world
        return float(np.linalg.norm(net))

    def push_into_contact(self, wrench_world: np.ndarray) -> float:
        """How hard a wrench on the TCP (6,) [N, Nm, world frame] pushes the robot into the
        environment along the robot-environment contact normal [N]: its virtual work per
        metre when the contact point moves into the environment along the normal, by the
        arm's least-norm joint motion (``dq = pinv(J_c) (-n)``, the TCP twist ``J_tcp dq``).
        ``n`` is the direction of the environment's net normal force on the robot and the
        contact point the contacts' force-weighted mean (``robot_contact_resultant``). A pure
        force on a contact at the TCP gives its component along ``-n``; a torque counts
        through the rotation that motion needs. 0 without such a contact; negative: it
        pulls away."""
        m, d = self.model, self.data
        if d.ncon == 0:
            return 0.0
        con, out = d.contact, self._resultant
        body = robot_contact_resultant(d.ncon, con.geom, con.efc_address, d.efc_force,
                                       con.frame, con.pos, self.geom_group, m.geom_bodyid, out)
        norm = float(np.linalg.norm(out[:3]))
        if body < 0 or norm == 0.0:
            return 0.0
        jac_c, jac_p, jac_r = self._jac_scratch
        mujoco.mj_jac(m, d, jac_c, None, out[3:], body)
        mujoco.mj_jacSite(m, d, jac_p, jac_r, self.tcp_site)
        dq = np.linalg.pinv(jac_c[:, self.arm_dof]) @ (-out[:3] / norm)
        twist = np.concatenate((jac_p[:, self.arm_dof] @ dq, jac_r[:, self.arm_dof] @ dq))
        return float(np.asarray(wrench_world, dtype=float) @ twist)

    def object_finger_contacts(self, object_body: str) -> int:
        """Number of finger-pad contacts touching ``object_body`` (privileged grasp check)."""
        m, d = self.model, self.data
        ncon = d.ncon
        if ncon == 0:
            return 0
        target = m.body(object_body).id
        return int(count_body_contacts(ncon, d.contact.geom, m.geom_bodyid, target,
                                        self._finger_bodies))
