"""ImpactController: impedance control + wrench estimation + internal-model feedforward (1 kHz).

Per tick (paper, Algorithm 1):
    tau = g + C dq + J^T (w_imp + w_ff + w_cmd) + N tau_posture, then rate limit and saturation
with w_ff = w_pred in mode "impact" and 0 in mode "impedance". The baseline ("impedance") runs
the estimator and slow filter (their signals exist) but skips the internal model entirely.
"""

from __future__ import annotations

import copy
from collections.abc import Iterator
from typing import Any, Literal

import numba
import numpy as np

from impact_control import kernels
from impact_control.arm_model import ArmDynamics, dynamics_arrays
from impact_control.config import ControllerConfig
from impact_control.contact_guard import ContactGuard
from impact_control.errors import InvalidArgumentError, SimulationError, check_choice
from impact_control.estimators import make_estimator
from impact_control.impedance import CartesianImpedance
from impact_control.internal_model import InternalModel
from impact_control.kernel_layout import (
    INPUT_ABS_MAX,
)
from impact_control.lie import invalid_quaternion
from impact_control.limits import TorqueLimiter
from impact_control.optional_stages import OptionalStages
from impact_control.signals import ControllerSignals
from impact_control.slow_filter import SlowWrenchFilter
from impact_control.validation import checked_gripper_command

__all__ = ["INPUT_ABS_MAX", "MODES", "ArmDynamics", "ControllerSignals", "ImpactController",
           "Mode", "describe_bad_input"]

Mode = Literal["impact", "impedance"]
CONTROLLERS: tuple[str, ...] = ("impedance", "impact")
"""The controller modes: the baseline impedance law and IMPACT. The one definition: the env,
impact-eval, impact-collect and impact-robot take their choices from here."""
MODES = CONTROLLERS


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


def named_arrays(prefix: str, value: object) -> Iterator[tuple[str, np.ndarray]]:
    """Every array in ``value`` (an array, a NamedTuple or tuple of them, nested), by dotted
    name: a NamedTuple field by its name, a plain tuple's item by its index. Scalars and
    None are skipped (no state)."""
    if isinstance(value, np.ndarray):
        yield prefix, value
    elif isinstance(value, tuple):
        names = getattr(value, "_fields", range(len(value)))
        for name, item in zip(names, value, strict=True):
            yield from named_arrays(f"{prefix}.{name}" if prefix else str(name), item)


class ImpactController:
    """Torque controller of the IMPACT paper for a 7-DoF arm.

    ``compute`` updates the dynamics and then runs every stage in one numba call
    (``kernels.controller_tick`` on ``kernel_state()``; the closed loop, ``impact_envs.loop``,
    runs the same kernel inside its own per-tick call); only the internal model's replay
    insert and SGD step run in Python/NumPy, on the ticks the kernel schedules them.

    Attributes:
        dynamics: Controller model, ``update``-d inside ``compute``.
        config: Controller configuration.
        mode: ``"impact"`` (feedforward applied) or ``"impedance"`` (baseline: the internal
            model is skipped entirely, w_pred reported as 0).
        internal_model: The learned wrench predictor (``save``/``load`` via safetensors).
        signals: ``ControllerSignals`` of the last tick.
    """

    STATELESS: tuple[str, ...] = ("_zeros6", "_zeros7")
    """Array attributes that carry nothing from one tick to the next (constants). Every
    other array of the controller and of its stages must be part of ``kernel_state()``
    (tests/envs/test_env_state.py checks it), so snapshots stay complete as stages are added."""

    def __init__(
        self,
        dynamics: ArmDynamics,
        config: ControllerConfig | None = None,
        mode: Mode = "impact",
    ) -> None:
        """Create all stages with preallocated buffers; call ``reset`` before ``compute``."""
        check_choice("controller mode", mode, MODES)
        self.dynamics = dynamics
        self.config = config or ControllerConfig()
        self.mode = mode
        cfg = self.config
        self.impedance = CartesianImpedance(cfg.impedance)
        self.estimator = make_estimator(cfg.estimator, cfg.dt_s)
        self.slow_filter = SlowWrenchFilter(cfg.slow_wrench, cfg.dt_s)
        self.internal_model = InternalModel(cfg.internal_model)
        self.limiter = TorqueLimiter(cfg.limits, cfg.dt_s)
        self.guard = ContactGuard(cfg.guard, cfg.dt_s,
                                  min(cfg.impedance.stiffness_translational_n_per_m))
        self.optional = OptionalStages(cfg.target_filter, cfg.observer, cfg.payload,
                                       cfg.joint_limits, cfg.dt_s,
                                       saturation_release=cfg.saturation_release)
        # Signal arrays alias the stages' output buffers (all written in place every tick).
        w_pred = self.internal_model.wrench_pred_world
        w_ext = (self.optional.observer.wrench_world if cfg.observer.enabled
                 else self.estimator.wrench_world)
        self.signals = ControllerSignals(
            pose_error=self.impedance.pose_error,
            wrench_imp_world=self.impedance.wrench_imp_world,
            wrench_ext_world=w_ext,
            wrench_slow_world=self.slow_filter.wrench_slow_world,
            wrench_pred_world=w_pred,
            tau_cmd=self.limiter.output,
        )
        self._init_buffers()
        self._is_reset = False
        self._tick_entry: Any = None

    def _init_buffers(self) -> None:
        """The controller's own state (``kernels.TickState``) and the estimator's."""
        cfg = self.config
        lam, lam_n = cfg.estimator.regularization, cfg.impedance.nullspace_pinv_damping
        self._tick_packed = kernels.make_tick_state(
            lam, lam_n, self.mode == "impact", self.mode == "impact" and cfg.payload.enabled)
        self.tick = kernels.unpack_tick(self._tick_packed.buffer, self._tick_packed.scalars)[0]
        self.signals.wrench_cmd_world = self.tick.wrench_cmd
        self.signals.wrench_ff_world = self.tick.wrench_ff
        self.estimator_map = self.tick.estimator_map  # (J J^T + lambda^2 I)^-1 J (6, n)
        self._zeros6, self._zeros7 = np.zeros(6), np.zeros(7)
        self._include_friction = cfg.estimator.include_joint_friction
        self._estimator_state = self.estimator.kernel_state()

    def reset(self, q0: np.ndarray, keep_internal_model: bool = False,
              resolve_tick: bool = True) -> None:
        """Start an episode at joint configuration ``q0`` [rad].

        Records q0 as the null-space posture, clears estimator, slow filter, gate, history and
        the torque-rate state (previous command without gravity := 0). With
        ``keep_internal_model=False`` the network is re-initialised (seeded) and its replay
        buffer cleared; with True the learned weights and replay persist across episodes.
        ``resolve_tick`` resolves ``compute``'s compiled tick here (a compile on a cold numba
        cache, ~1.2 ms of type lookup on a warm one), so that the first ``compute`` of a timed
        loop does not pay it; a caller that ticks through its own compiled loop instead (the
        simulated env's closed loop, which inlines the same tick) passes False and pays nothing
        for an entry it never calls (``compute`` still resolves it on first use).
        """
        q0 = np.asarray(q0, dtype=float)
        if q0.shape != (7,) or not np.all(np.isfinite(q0)):
            raise InvalidArgumentError(f"invalid q0 {q0!r}; valid: finite array of shape (7,)")
        self.impedance.set_posture(q0)
        self.estimator.reset()
        self.slow_filter.reset()
        self.limiter.reset()
        self.guard.reset()
        self.optional.reset()
        if keep_internal_model:
            self.internal_model.reset_history()
        else:
            self.internal_model.reinitialize()
        self.signals.clear()
        self._is_reset = True
        if resolve_tick and self._tick_entry is None:  # now, not in the first tick
            self._entry(self._kernel_args(q0, self._zeros7, self._zeros7, np.zeros(3),
                                          np.array([1.0, 0.0, 0.0, 0.0]), None,
                                          self.internal_model.mask_array(None), 0.0))

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
        gripper_cmd: float | None = None,
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
            gripper_cmd: The gripper command (-1 open ... +1 closed) from this tick on, read
                by the payload model's gripper hold-off (None: the last one given; +1 after
                ``reset``).

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
        mask = self.internal_model.mask_array(learn_mask)
        grip = None if gripper_cmd is None else checked_gripper_command(gripper_cmd)
        args = self._kernel_args(q, dq, tau_measured, pos_target_world, quat_target_world,
                                 wrench_cmd_world, mask, gripper_width_m)
        if grip is not None:
            self.optional.payload.state.gripper_cmd[0] = grip
        flags = self._entry(args)(*args, self.kernel_state())
        if flags:
            self._after_tick(flags, quat_target_world, mask)
        self._fill_signals()
        return self.limiter.output.copy()

    def set_gripper_command(self, gripper_cmd: float) -> None:
        """The gripper command (-1 open ... +1 closed) for the next ticks: what the payload
        model's gripper hold-off reads (the closed loop sets it once per policy step)."""
        self.optional.payload.state.gripper_cmd[0] = checked_gripper_command(gripper_cmd)

    def _kernel_args(self, q: np.ndarray, dq: np.ndarray, tau_measured: np.ndarray,
                     pos_target_world: np.ndarray, quat_target_world: np.ndarray,
                     wrench_cmd_world: np.ndarray | None, mask: np.ndarray,
                     gripper_width_m: float) -> tuple:
        """Checked float64 inputs of ``kernels.controller_tick`` (all but the state), after
        updating the dynamics at (q, dq); a refused input leaves everything untouched."""
        f64 = np.float64
        _check_shapes(q=(q, 7), dq=(dq, 7), tau_measured=(tau_measured, 7),
                      pos_target_world=(pos_target_world, 3),
                      quat_target_world=(quat_target_world, 4),
                      wrench_cmd_world=(wrench_cmd_world, 6))
        c64 = np.ascontiguousarray  # a C-contiguous float64 array passes as itself
        cmd = self._zeros6 if wrench_cmd_world is None else c64(wrench_cmd_world, f64)
        inputs = (c64(q, f64), c64(dq, f64), c64(tau_measured, f64),
                  c64(pos_target_world, f64), c64(quat_target_world, f64), cmd)
        if kernels.first_bad_input(*inputs, float(gripper_width_m)) >= 0:
            raise InvalidArgumentError(describe_bad_input(*inputs, gripper_width_m))
        dyn = self.dynamics
        dyn.update(inputs[0], inputs[1])
        fric = dyn.joint_friction(inputs[1]) if self._include_friction else self._zeros7
        return (*inputs, mask, float(gripper_width_m), c64(fric, f64),
                dynamics_arrays(dyn))

    def _entry(self, args: tuple) -> Any:
        """``controller_tick`` compiled for these argument types, resolved by the first ``reset``
        (the type lookup costs ~1.2 ms once, more than a tick's budget):
        calling it skips numba's per-call type dispatch (tens of microseconds for the named
        state; the closed loop does the same). The inputs are C-contiguous float64 arrays
        (``_kernel_args``), the state's arrays are this controller's own: the types never
        change."""
        if self._tick_entry is None:
            types = tuple(numba.typeof(a) for a in (*args, self.kernel_state()))
            self._tick_entry = kernels.controller_tick.compile(types)
        return self._tick_entry

    def kernel_state(self) -> kernels.ControllerState:
        """The buffers of ``kernels.controller_tick`` as one named structure (views: what the
        kernel writes is this controller's state)."""
        model32, weights, biases, model, learner = self.internal_model.kernel_args()
        return kernels.ControllerState(
            tick=self._tick_packed,
            est=self._estimator_state, sf=self.slow_filter.packed, model32=model32,
            weights=weights, biases=biases, model=model, learner=learner,
            guard=self.guard.packed, imp=self.impedance.packed, opt=self.optional.packed,
            lim=self.limiter.packed)

    def state_arrays(self) -> dict[str, np.ndarray]:
        """Every array that carries this controller from one tick to the next, by name, live
        (the kernel's own buffers): ``kernel_state()`` walked generically (``named_arrays``),
        so a stage whose state is a field of ``kernels.ControllerState`` is in every
        snapshot (``ImpactEnv.get_state``) with no code of its own."""
        return dict(named_arrays("", self.kernel_state()))

    def python_state(self) -> dict[str, Any]:
        """The controller's state that is not an array, as copies (``load_python_state``)."""
        return {"is_reset": self._is_reset, **self.internal_model.python_state()}

    def load_python_state(self, state: dict[str, Any]) -> None:
        """Set what ``python_state`` returned (copied) and refresh ``signals``."""
        state = copy.deepcopy(state)
        self._is_reset = bool(state.pop("is_reset"))
        self.internal_model.load_python_state(state)
        self._fill_signals()

    def loop_inputs(self, wrench_cmd_world: np.ndarray | None = None,
                    learn_mask: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(wrench_cmd_world, learn mask)`` as ``controller_tick`` reads them, for a caller
        that runs sensing, the model update, this kernel and actuation in one numba call per
        tick (``impact_envs.loop``); pass each call's status bits to ``finish_tick``: torques
        and signals are then exactly those ``compute`` gives for the same readings (tested).

        Raises:
            InvalidArgumentError: Before ``reset``, or when the estimator models joint
                friction that is not identically zero (the loop feeds none).
        """
        if not self._is_reset:
            raise InvalidArgumentError("invalid call order; valid: reset(q0) before compute()")
        if self._include_friction and not getattr(self.dynamics, "joint_friction_is_zero", False):
            raise InvalidArgumentError(
                "the closed loop feeds no joint-friction model; valid: dynamics whose "
                "joint_friction is identically zero, or estimator.include_joint_friction=False")
        cmd = (self._zeros6 if wrench_cmd_world is None
               else np.asarray(wrench_cmd_world, np.float64))
        return cmd, self.internal_model.mask_array(learn_mask)

    def finish_tick(self, flags: int, quat_target_world: np.ndarray,
                    learn_mask: np.ndarray | None = None) -> None:
        """After a ``controller_tick`` run by the closed loop: errors, scheduled learning,
        ``signals``."""
        if flags:
            self._after_tick(flags, quat_target_world,
                             self.internal_model.mask_array(learn_mask))
        self._fill_signals()

    def _after_tick(self, flags: int, quat_target_world: np.ndarray, mask: np.ndarray) -> None:
        """Raise on bad input / non-finite torque; run the scheduled replay insert / SGD step."""
        if flags & kernels.BAD_QUAT:
            raise invalid_quaternion(quat_target_world)
        if flags & (kernels.STORE | kernels.TRAIN):
            self.internal_model.learn(flags, self.guard.target, mask)
        if flags & kernels.DIVERGED:
            self.internal_model.diverged()
        if flags & kernels.NON_FINITE:
            raise SimulationError(f"non-finite torque command {self.limiter.output!r}")

    def _fill_signals(self) -> None:
        """Copy the kernel's scalar outputs into ``signals`` (the arrays are aliases)."""
        sig = self.signals
        t = self.tick
        e_pos, e_rot, rate = t.pos_error_norm[0], t.rot_error_norm[0], t.slow_rate[0]
        surprise, gate, learning = t.surprise[0], t.gate_open[0], t.learning_active[0]
        sig.pos_error_norm_m, sig.rot_error_norm_rad = e_pos, e_rot
        sig.slow_wrench_rate, sig.surprise_n = rate, surprise
        sig.gate_open, sig.learning_active = gate != 0.0, learning != 0.0
