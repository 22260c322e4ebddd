"""The controller's model of the arm: Pinocchio built from the same MJCF the simulator loads.

The finger joints are locked (``buildReducedModel``) at a fixed opening, so the model has the
7 arm joints. Rotor armature is part of the mass matrix (Pinocchio's ``crba`` adds it), as in
MuJoCo. The model can be perturbed on purpose to study model error.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from impact_control.chain_dynamics import (
    ChainParams,
    ModelArrays,
    chain_terms,
    make_workspace,
)
from impact_control.errors import InvalidArgumentError

ROBOT_XML = Path(__file__).resolve().parent / "assets" / "fr3_hand.xml"
"""The robot-only MJCF (one root body at the identity pose)."""

ARM_JOINTS = tuple(f"fr3_joint{i}" for i in range(1, 8))
FINGER_JOINTS = ("finger_joint1", "finger_joint2")
TCP_FRAME = "tcp"
LOCAL_WORLD_ALIGNED = pin.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class ModelPerturbation:
    """Deliberate error in the controller's inertial model (the simulator is unchanged).

    Attributes:
        link_mass_scale: factor applied to every link's mass and rotational inertia [-].
        link_mass_noise: std of an extra per-link relative factor ``1 + noise * N(0, 1)`` on
            mass and rotational inertia [-].
        com_noise_m: std of a per-link centre-of-mass shift, per axis of the link frame [m].
        inertia_noise: std of a further per-link relative factor on the rotational inertia
            alone [-] (clipped to keep it positive).
        seed: seed of the per-link noise (the three kinds draw from separate streams, so
            one's draws do not depend on whether another is on).
    """

    link_mass_scale: float = 1.0
    link_mass_noise: float = 0.0
    com_noise_m: float = 0.0
    inertia_noise: float = 0.0
    seed: int = 0

    def __post_init__(self) -> None:
        if not self.link_mass_scale > 0.0:
            raise InvalidArgumentError(
                f"link_mass_scale must be > 0, got {self.link_mass_scale}"
            )
        for name, high in (("link_mass_noise", 0.5), ("inertia_noise", 0.5),
                           ("com_noise_m", 0.05)):
            if not 0.0 <= getattr(self, name) < high:
                raise InvalidArgumentError(
                    f"{name} must be in [0, {high:g}), got {getattr(self, name)}")


def _perturb(model: pin.Model, perturbation: ModelPerturbation) -> None:
    rng = np.random.default_rng(perturbation.seed)
    com_rng = np.random.default_rng([perturbation.seed, 1])
    inertia_rng = np.random.default_rng([perturbation.seed, 2])
    for i in range(1, model.njoints):
        factor = perturbation.link_mass_scale * (
            1.0 + perturbation.link_mass_noise * rng.standard_normal()
        )
        inertia = model.inertias[i]
        lever = inertia.lever.copy() + perturbation.com_noise_m * com_rng.standard_normal(3)
        rot_factor = max(1.0 + perturbation.inertia_noise * inertia_rng.standard_normal(), 0.1)
        model.inertias[i] = pin.Inertia(
            inertia.mass * factor, lever, inertia.inertia * factor * rot_factor
        )


class PinocchioArm:
    """Kinematics and rigid-body dynamics of the 7-DoF arm at the TCP.

    Call :meth:`update` once per control tick, then read the cached attributes:
    ``pos_ee_world`` (3,) [m], ``rot_ee_world`` (3, 3), ``jacobian`` (6, 7) world-aligned at the
    TCP with rows (linear; angular), ``mass_matrix`` (7, 7) [kg m^2] incl. armature,
    ``gravity`` (7,) [Nm], ``coriolis_matrix`` (7, 7) [Nm s] (refreshed only while
    ``need_coriolis``); ``nonlinear`` (7,) = C q' + g [Nm] is computed when read.

    Args:
        xml_path: robot MJCF; defaults to the shipped FR3 + Hand.
        finger_opening_m: opening of each finger at which the fingers are locked [m].
        perturbation: optional deliberate inertial model error.
    """

    n: int = 7

    STATELESS: tuple[str, ...] = (
        "damping", "q_lower", "q_upper", "torque_limits",  # the model's constants
        "pos_ee_world", "rot_ee_world", "jacobian", "mass_matrix", "gravity",
        "coriolis_matrix", "q_model", "dq_model", "chain_work")  # recomputed by every update
    """Arrays that carry nothing a controller snapshot must restore (``get_state``): the
    model's constants, and the terms ``update`` (or the closed loop's ``chain_terms``)
    recomputes from (q, dq) every tick before any stage reads them, with their scratch."""

    def __init__(
        self,
        xml_path: str | Path | None = None,
        *,
        finger_opening_m: float = 0.02,
        perturbation: ModelPerturbation | None = None,
    ) -> None:
        full = pin.buildModelFromMJCF(str(xml_path or ROBOT_XML))
        q_lock = pin.neutral(full)
        lock_ids = []
        for name in FINGER_JOINTS:
            jid = full.getJointId(name)
            lock_ids.append(jid)
            q_lock[full.joints[jid].idx_q] = finger_opening_m
        self.model: pin.Model = pin.buildReducedModel(full, lock_ids, q_lock)
        if perturbation is not None:
            _perturb(self.model, perturbation)
        if list(self.model.names)[1:] != list(ARM_JOINTS):
            raise InvalidArgumentError(f"unexpected joints in {xml_path}: {list(self.model.names)}")
        self.data = self.model.createData()
        self._tcp = self.model.getFrameId(TCP_FRAME)
        self.damping = np.asarray(self.model.damping, dtype=float).copy()
        self.q_lower = np.asarray(self.model.lowerPositionLimit, dtype=float).copy()
        self.q_upper = np.asarray(self.model.upperPositionLimit, dtype=float).copy()
        self.torque_limits = np.asarray(self.model.effortLimit, dtype=float).copy()
        self.pos_ee_world = np.zeros(3)
        self.rot_ee_world = np.eye(3)
        self.jacobian = np.zeros((6, 7))
        self.mass_matrix = np.eye(7)
        self.gravity = np.zeros(7)
        self.coriolis_matrix = np.zeros((7, 7))
        self.need_coriolis = True
        self.q_model, self.dq_model = np.zeros(7), np.zeros(7)  # where the model was evaluated
        self._nle_data = self.model.createData()
        self.chain = ChainParams.from_pinocchio(self.model, self._tcp)
        """``ChainParams`` of ``chain_terms`` (the closed loop calls it inside its tick)."""
        self.chain_work = make_workspace(self.n)
        self.model_arrays = ModelArrays(self.pos_ee_world, self.rot_ee_world, self.jacobian,
                                        self.mass_matrix, self.gravity, self.coriolis_matrix)
        """The cached attributes as ``chain_terms`` writes them (the same arrays)."""
        self.joint_friction_is_zero = True  # see joint_friction: the sensor is link-side

    def state_arrays(self) -> dict[str, np.ndarray]:
        """Where the model was last evaluated and what it cached there, by name, live (a
        restored controller reads them before its next ``update``)."""
        return {"q_model": self.q_model, "dq_model": self.dq_model,
                **{f"arm_{k}": v for k, v in self.model_arrays._asdict().items()}}

    def update(self, q: np.ndarray, dq: np.ndarray) -> None:
        """Recompute every cached quantity at joint positions ``q`` [rad], velocities ``dq``.

        One numba call (``chain_dynamics.chain_terms``, parameters read from this Pinocchio model
        and tested against Pinocchio to 1e-12); the arrays are updated in place.
        ``coriolis_matrix`` is refreshed only when ``need_coriolis`` is True (the controller
        needs it every tick). Its factorization differs from ``pin.computeCoriolisMatrix``'s
        (C is not unique) but C dq and C^T dq, the only products the controller forms, agree.
        """
        self.q_model[:] = q
        self.dq_model[:] = dq
        chain_terms(self.chain, self.q_model, self.dq_model, self.need_coriolis, self.chain_work,
                    self.model_arrays)

    @property
    def nonlinear(self) -> np.ndarray:
        """C(q, dq) dq + g(q) [Nm] at the last ``update`` (RNEA on demand, a new array)."""
        return pin.nonLinearEffects(self.model, self._nle_data, self.q_model, self.dq_model).copy()

    def joint_friction(self, dq: np.ndarray) -> np.ndarray:
        """Joint friction torque [Nm] that the torque sensor does NOT see, for the residual.

        The simulated joint-torque sensor sits on the link side of the transmission, after
        joint damping and Coulomb friction (docs/sensing.md), so the friction a residual
        estimator must model is zero. ``self.damping`` keeps the MJCF viscous coefficients.
        """
        return np.zeros(len(dq))
