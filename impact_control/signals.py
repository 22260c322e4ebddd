"""What the controller reports every tick (overwritten in place; ``copy()`` to keep it)."""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np


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
