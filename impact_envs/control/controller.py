"""ImpactController: impedance control + wrench estimation + internal-model feedforward (1 kHz).

Per tick (paper, Algorithm 1):
    tau = g + C dq + J^T (w_imp + w_ff + w_cmd) + N tau_posture, then rate limit and saturation
with w_ff = w_pred in mode "impact" and 0 in mode "impedance". The baseline ("impedance") runs
the estimator and slow filter (their signals exist) but skips the internal model entirely.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Literal

import numpy as np
import torch

from impact_envs.control import kernels
from impact_envs.control.config import ControllerConfig
from impact_envs.control.estimators import make_estimator
from impact_envs.control.impedance import CartesianImpedance
from impact_envs.control.internal_model import InternalModel
from impact_envs.control.kernel_layout import INPUT_ABS_MAX
from impact_envs.control.lie import invalid_quaternion
from impact_envs.control.limits import TorqueLimiter
from impact_envs.control.protocols import ArmDynamics, dynamics_arrays
from impact_envs.control.slow_filter import SlowWrenchFilter
from impact_envs.errors import InvalidArgumentError, SimulationError, check_choice

__all__ = ["INPUT_ABS_MAX", "MODES", "ArmDynamics", "ControllerSignals", "ImpactController",
           "Mode", "describe_bad_input"]

Mode = Literal["impact", "impedance"]
MODES: tuple[str, ...] = ("impact", "impedance")


def _zeros(n: int) -> np.ndarray:
    return np.zeros(n)


@dataclass
class ControllerSignals:
    """Signals of the last tick, overwritten in place every tick (``copy()`` to keep them).

    Wrenches are (force [N], torque [Nm]) in the world frame, robot-on-environment sign.

    Attributes:
        pose_error: [p_d - p [m]; Log(R_d R^T) [rad]] (6,).
        pos_error_norm_m: |p_d - p| [m].
        rot_error_norm_rad: |Log(R_d R^T)| [rad].
        wrench_imp_world: Impedance wrench K e - D J dq (6,).
        wrench_ext_world: Raw estimate w_hat from the estimator (6,).
        wrench_slow_world: Slow wrench w_slow (6,).
        wrench_pred_world: Internal model prediction w_pred (6,) (0 in mode "impedance",
            which skips the internal model).
        wrench_ff_world: Applied feedforward (6,): w_pred in "impact" (on an axis masked by
            ``learn_mask``: held at its last unmasked value), 0 in "impedance".
        wrench_cmd_world: Explicit commanded wrench applied this tick (6,).
        slow_wrench_rate: Dimensionless slow-wrench rate (see SlowWrenchFilter).
        surprise_n: Force surprise |w_pred - w_slow| on unmasked axes [N].
        gate_open: Latched state of the surprise gate.
        learning_active: Gate open and slow wrench quasi-steady on this tick.
        tau_cmd: Torque sent after rate limiting and saturation (7,) [Nm].
    """

    pose_error: np.ndarray = field(default_factory=lambda: _zeros(6))
    pos_error_norm_m: float = 0.0
    rot_error_norm_rad: float = 0.0
    wrench_imp_world: np.ndarray = field(default_factory=lambda: _zeros(6))
    wrench_ext_world: np.ndarray = field(default_factory=lambda: _zeros(6))
    wrench_slow_world: np.ndarray = field(default_factory=lambda: _zeros(6))
    wrench_pred_world: np.ndarray = field(default_factory=lambda: _zeros(6))
    wrench_ff_world: np.ndarray = field(default_factory=lambda: _zeros(6))
    wrench_cmd_world: np.ndarray = field(default_factory=lambda: _zeros(6))
    slow_wrench_rate: float = 0.0
    surprise_n: float = 0.0
    gate_open: bool = False
    learning_active: bool = False
    tau_cmd: np.ndarray = field(default_factory=lambda: _zeros(7))

    def clear(self) -> None:
        """Zero every value in place (references to the arrays stay valid)."""
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, np.ndarray):
                v.fill(0.0)
            else:
                setattr(self, f.name, type(v)())

    def copy(self) -> ControllerSignals:
        """Deep copy (arrays copied) for logging."""
        values = {}
        for f in fields(self):
            v = getattr(self, f.name)
            values[f.name] = v.copy() if isinstance(v, np.ndarray) else v
        return ControllerSignals(**values)


def limit_torch_threads() -> None:
    """Set torch's intra-op threads to 1 when it has more (process-wide).

    The SGD steps of the internal model are tiny (batch 16); extra threads only add
    synchronisation and compete with the simulation for cores.
    """
    if torch.get_num_threads() > 1:
        torch.set_num_threads(1)


def _check_shapes(**arrays: tuple[np.ndarray | None, int]) -> None:
    """One-line ``InvalidArgumentError`` unless each given array has shape ``(n,)``: the numba
    kernels index fixed sizes, so a short array would be read out of bounds."""
    for name, (value, n) in arrays.items():
        if value is not None and np.shape(value) != (n,):
            raise InvalidArgumentError(f"{name} must have shape ({n},), got {np.shape(value)}")


def describe_bad_input(q: np.ndarray, dq: np.ndarray, tau_measured: np.ndarray,
                       pos_target_world: np.ndarray, quat_target_world: np.ndarray,
                       wrench_cmd_world: np.ndarray, gripper_width_m: float) -> str:
    """One line naming the first input outside ``INPUT_ABS_MAX`` (the kernels' check)."""
    values = (q, dq, tau_measured, pos_target_world, quat_target_world, wrench_cmd_world)
    arrays = [np.asarray(v, dtype=np.float64) for v in values]
    i = int(kernels.first_bad_input(*arrays, float(gripper_width_m)))
    if i < 0:
        return "every input within range"
    name, bound, unit = INPUT_ABS_MAX[i]
    value = gripper_width_m if i == 6 else arrays[i].tolist()
    return (f"invalid {name} {value}; valid: finite values with |x| <= {bound:g}"
            + (f" {unit}" if unit else ""))


class ImpactController:
    """Torque controller of the IMPACT paper for a 7-DoF arm.

    ``compute`` updates the dynamics and then runs every stage in one numba call
    (``kernels.controller_tick``; with a dynamics object that exposes ``chain_params``,
    ``chain_work`` and ``chain_state`` (``PinocchioArm``) the model update is part of the same
    call, ``kernels.controller_tick_chain``); only the internal model's replay insert and SGD
    step run in Python/NumPy, on the ticks the kernel schedules them. Creating a controller calls
    ``limit_torch_threads`` (torch intra-op threads := 1 when higher, process-wide).

    Attributes:
        dynamics: Controller model, ``update``-d inside ``compute``.
        config: Controller configuration.
        mode: ``"impact"`` (feedforward applied) or ``"impedance"`` (baseline: the internal
            model is skipped entirely, w_pred reported as 0).
        internal_model: The learned wrench predictor (``save``/``load`` via safetensors).
        signals: ``ControllerSignals`` of the last tick.
    """

    def __init__(
        self,
        dynamics: ArmDynamics,
        config: ControllerConfig | None = None,
        mode: Mode = "impact",
    ) -> None:
        """Create all stages with preallocated buffers; call ``reset`` before ``compute``."""
        check_choice("controller mode", mode, MODES)
        limit_torch_threads()
        self.dynamics = dynamics
        self.config = config or ControllerConfig()
        self.mode = mode
        cfg = self.config
        self.impedance = CartesianImpedance(cfg.impedance)
        self.estimator = make_estimator(cfg.estimator, cfg.dt_s)
        self.slow_filter = SlowWrenchFilter(cfg.slow_wrench, cfg.dt_s)
        self.internal_model = InternalModel(cfg.internal_model)
        self.limiter = TorqueLimiter(cfg.limits, cfg.dt_s)
        # Signal arrays alias the stages' output buffers (all written in place every tick).
        w_pred = self.internal_model.wrench_pred_world
        self.signals = ControllerSignals(
            pose_error=self.impedance.pose_error,
            wrench_imp_world=self.impedance.wrench_imp_world,
            wrench_ext_world=self.estimator.wrench_world,
            wrench_slow_world=self.slow_filter.wrench_slow_world,
            wrench_pred_world=w_pred,
            tau_cmd=self.limiter.output,
        )
        self._init_buffers()
        self._is_reset = False

    def _init_buffers(self) -> None:
        """Controller buffer (``kernels.controller_views``) and the wrench-map solves."""
        cfg = self.config
        lam, lam_n = cfg.estimator.regularization, cfg.impedance.nullspace_pinv_damping
        self.buffer = np.zeros(kernels.CONTROLLER_SIZE)
        views = kernels.controller_views(self.buffer)
        par, self.signals.wrench_cmd_world, _, self._scalars = views[:4]
        self.signals.wrench_ff_world = views[4]
        run_model = self.mode == "impact"
        par[:] = (lam * lam, lam_n * lam_n, float(lam_n == lam), self.estimator.kernel_kind,
                  float(run_model), float(run_model))
        self._grams = np.zeros((2, 6, 6))
        self.wrench_maps = np.zeros((2, 6, 7))  # estimator's (J J^T + l^2 I)^-1 J, projector's
        self._zeros6, self._zeros7 = np.zeros(6), np.zeros(7)
        self._include_friction = cfg.estimator.include_joint_friction
        # kernels.controller_tick arguments around the internal model's (fixed arrays)
        self._stage_buffers = (self.buffer, self._grams, self.wrench_maps,
                               self.estimator.buffer, self.slow_filter.buffer)
        self._law_buffers = (self.impedance.buffer, self.limiter.buffer)

    def reset(self, q0: np.ndarray, keep_internal_model: bool = False) -> None:
        """Start an episode at joint configuration ``q0`` [rad].

        Records q0 as the null-space posture, clears estimator, slow filter, gate, history and
        the torque-rate state (previous command without gravity := 0). With
        ``keep_internal_model=False`` the network is re-initialised (seeded) and its replay
        buffer cleared; with True the learned weights and replay persist across episodes.
        """
        q0 = np.asarray(q0, dtype=float)
        if q0.shape != (7,) or not np.all(np.isfinite(q0)):
            raise InvalidArgumentError(f"invalid q0 {q0!r}; valid: finite array of shape (7,)")
        self.impedance.set_posture(q0)
        self.estimator.reset()
        self.slow_filter.reset()
        self.limiter.reset()
        if keep_internal_model:
            self.internal_model.reset_history()
        else:
            self.internal_model.reinitialize()
        self.signals.clear()
        self._is_reset = True

    def compute(
        self,
        q: np.ndarray,
        dq: np.ndarray,
        tau_measured: np.ndarray,
        pos_target_world: np.ndarray,
        quat_target_world: np.ndarray,
        wrench_cmd_world: np.ndarray | None = None,
        learn_mask: np.ndarray | None = None,
        gripper_width_m: float = 0.0,
    ) -> np.ndarray:
        """One 1 kHz control tick.

        Args:
            q: Joint positions (7,) [rad].
            dq: Joint velocities (7,) [rad/s].
            tau_measured: Joint torque sensor reading (7,) [Nm].
            pos_target_world: Desired TCP position (3,) [m].
            quat_target_world: Desired TCP orientation (w, x, y, z).
            wrench_cmd_world: Optional explicit wrench the robot should apply to the
                environment (6,) [N, Nm], added as J^T w_cmd (hybrid force control).
            learn_mask: Optional 6 bools; False freezes internal-model learning on that axis
                and holds its feedforward at the value of the last tick it was unmasked.
            gripper_width_m: Finger opening [m] (0 ... 0.08), an internal-model feature.

        Returns:
            Torque command (7,) [Nm] after torque-rate limiting and saturation (a new array).

        Raises:
            InvalidArgumentError: If an array has the wrong shape, an input is not finite or
                beyond ``INPUT_ABS_MAX`` (the controller is then left as it was), or the
                target quaternion is zero.
            SimulationError: If the command is not finite.
        """
        if not self._is_reset:
            raise InvalidArgumentError("invalid call order; valid: reset(q0) before compute()")
        dyn = self.dynamics
        chain = getattr(dyn, "chain_params", None)
        mask = self.internal_model.mask_array(learn_mask)
        args = self._kernel_args(q, dq, tau_measured, pos_target_world, quat_target_world,
                                 wrench_cmd_world, mask, gripper_width_m)
        if chain is None:
            flags = kernels.controller_tick(*args)
        else:  # the model update runs inside the same numba call
            flags = kernels.controller_tick_chain(chain, dyn.chain_work, bool(dyn.need_coriolis),
                                                  *dyn.chain_state, *args)
        if flags & kernels.BAD_INPUT:
            raise InvalidArgumentError(describe_bad_input(*args[:6], args[7]))
        if flags:
            self._after_tick(flags, quat_target_world, mask)
        self._fill_signals()
        return self.limiter.output.copy()

    def _kernel_args(self, q: np.ndarray, dq: np.ndarray, tau_measured: np.ndarray,
                     pos_target_world: np.ndarray, quat_target_world: np.ndarray,
                     wrench_cmd_world: np.ndarray | None, mask: np.ndarray,
                     gripper_width_m: float) -> tuple:
        """Shape-checked float64 inputs and buffers of ``kernels.controller_tick`` (updates the
        dynamics first where they are not computed inside the kernel)."""
        f64 = np.float64
        q, dq = np.asarray(q, dtype=f64), np.asarray(dq, dtype=f64)
        _check_shapes(q=(q, 7), dq=(dq, 7), tau_measured=(tau_measured, 7),
                      pos_target_world=(pos_target_world, 3),
                      quat_target_world=(quat_target_world, 4),
                      wrench_cmd_world=(wrench_cmd_world, 6))
        dyn = self.dynamics
        cmd = self._zeros6 if wrench_cmd_world is None else np.asarray(wrench_cmd_world, f64)
        if getattr(dyn, "chain_params", None) is None:  # else the kernel checks, then updates
            inputs = (q, dq, np.asarray(tau_measured, f64), np.asarray(pos_target_world, f64),
                      np.asarray(quat_target_world, f64), cmd)
            if kernels.first_bad_input(*inputs, float(gripper_width_m)) >= 0:
                raise InvalidArgumentError(describe_bad_input(*inputs, gripper_width_m))
            dyn.update(q, dq)
        fric = dyn.joint_friction(dq) if self._include_friction else self._zeros7
        return (
            q, dq, np.asarray(tau_measured, f64), np.asarray(pos_target_world, f64),
            np.asarray(quat_target_world, f64), cmd, mask, float(gripper_width_m),
            np.asarray(fric, f64), dynamics_arrays(dyn), *self._stage_buffers,
            *self.internal_model.kernel_args(), *self._law_buffers,
        )  # fmt: skip

    def fused_inputs(
        self,
        wrench_cmd_world: np.ndarray | None = None,
        learn_mask: np.ndarray | None = None,
    ) -> tuple[tuple, tuple] | None:
        """Arguments of ``kernels.controller_tick_chain`` for a caller that fuses sensing,
        control and actuation into one numba call (``impact_envs.robot.loop``).

        Returns ``(head, tail)``: the call is ``controller_tick_chain(*head, q, dq, tau,
        pos_target, quat_target, *tail[:2], gripper_width, *tail[2:])``; ``None`` when this
        controller cannot be fused (dynamics without a chain kernel, or a joint-friction model
        in the estimator that is not identically zero). Pass the call's result to
        ``finish_tick``: torques and signals are then exactly those ``compute`` gives for the
        same readings (tested).
        """
        dyn = self.dynamics
        chain = getattr(dyn, "chain_params", None)
        friction = self._include_friction and not getattr(dyn, "joint_friction_is_zero", False)
        if chain is None or friction:
            return None
        if not self._is_reset:
            raise InvalidArgumentError("invalid call order; valid: reset(q0) before compute()")
        cmd = (self._zeros6 if wrench_cmd_world is None
               else np.asarray(wrench_cmd_world, np.float64))
        head = (chain, dyn.chain_work, bool(dyn.need_coriolis), *dyn.chain_state)
        tail = (cmd, self.internal_model.mask_array(learn_mask), self._zeros7,
                dynamics_arrays(dyn), *self._stage_buffers, *self.internal_model.kernel_args(),
                *self._law_buffers)
        return head, tail

    def finish_tick(self, flags: int, quat_target_world: np.ndarray,
                    learn_mask: np.ndarray | None = None) -> None:
        """Second half of a fused tick: errors, scheduled learning, ``signals``."""
        if flags:
            self._after_tick(flags, quat_target_world,
                             self.internal_model.mask_array(learn_mask))
        self._fill_signals()

    def _after_tick(self, flags: int, quat_target_world: np.ndarray, mask: np.ndarray) -> None:
        """Raise on bad input / non-finite torque; run the scheduled replay insert / SGD step."""
        if flags & kernels.BAD_QUAT:
            raise invalid_quaternion(quat_target_world)
        if flags & (kernels.STORE | kernels.TRAIN):
            self.internal_model.learn(flags, self.slow_filter.wrench_slow_world, mask)
        if flags & kernels.NON_FINITE:
            raise SimulationError(f"non-finite torque command {self.limiter.output!r}")

    def _fill_signals(self) -> None:
        """Copy the kernel's scalar outputs into ``signals`` (the arrays are aliases)."""
        sig = self.signals
        e_pos, e_rot, rate, surprise, gate, learning = self._scalars.tolist()
        sig.pos_error_norm_m, sig.rot_error_norm_rad = e_pos, e_rot
        sig.slow_wrench_rate, sig.surprise_n = rate, surprise
        sig.gate_open, sig.learning_active = gate != 0.0, learning != 0.0
