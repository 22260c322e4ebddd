"""``ImpedanceConfig``: the settings of the impedance law (``impedance.py``, which re-exports
it), with units and frames in the names; options the authors' released controller uses are
described in ``impedance_options.py``."""

from __future__ import annotations

import math
from dataclasses import dataclass

from impact_control.errors import InvalidArgumentError, check_choice
from impact_control.validation import (
    FRAMES,
    check_len,
    check_optional_positive,
    check_positive,
)


@dataclass(frozen=True)
class ImpedanceConfig:
    """Task-space impedance, null-space posture and model compensation terms.

    Attributes:
        stiffness_translational_n_per_m: Diagonal of K for position error [N/m] (paper: 400).
        stiffness_rotational_nm_per_rad: Diagonal of K for orientation error [Nm/rad] (paper: 30).
        damping_translational_ns_per_m: Diagonal of D for TCP linear velocity [N s/m] (paper: 40).
        damping_rotational_nms_per_rad: Diagonal of D for TCP angular velocity [Nm s/rad]
            (paper: 10.95 = 2 sqrt(30)).
        nullspace_stiffness_nm_per_rad: Joint stiffness k_n toward the posture q_null that
            ``reset`` records [Nm/rad] (own choice: 10).
        nullspace_damping_nms_per_rad: Joint damping d_n of the posture task [Nm s/rad];
            ``None`` means 2 sqrt(k_n) (Franka example convention).
        nullspace_pinv_damping: Damping of the pseudo-inverse in N = I - J^T (J^+)^T
            [units of J]. Equal to the estimator's lambda by default so one regularized solve
            per tick serves both.
        compensate_gravity: Add g(q) of the controller model (the simulation has none built in).
        compensate_coriolis: Add C(q, dq) dq (as the Franka example does).
        gains_frame: ``"world"`` (default) or ``"tcp"``: the frame whose axes K, D and the
            error clip act on (``impedance_options.py``; the authors: ``"tcp"``).
        pose_error_clip_m: Per-axis bound on the position error in the gains frame [m]
            (None: none; the authors' robot: 0.1, their simulation: none).
        pose_error_clip_rad: Per-axis bound on the orientation error [rad] (None; 0.5).
        nullspace_torque_max_nm: Per-joint bound on the projected null-space torque [Nm]
            (None: none; the authors: 5).

    ``nullspace_damping_nms_per_rad`` may be negative: the authors' controller runs -1 (its
    schema says "negative -> 2 sqrt(k)", its code multiplies by -1: energy is injected along
    the null space); ``None`` is that intended variant.
    """

    stiffness_translational_n_per_m: tuple[float, float, float] = (400.0, 400.0, 400.0)
    stiffness_rotational_nm_per_rad: tuple[float, float, float] = (30.0, 30.0, 30.0)
    damping_translational_ns_per_m: tuple[float, float, float] = (40.0, 40.0, 40.0)
    damping_rotational_nms_per_rad: tuple[float, float, float] = (10.95, 10.95, 10.95)
    nullspace_stiffness_nm_per_rad: float = 10.0
    nullspace_damping_nms_per_rad: float | None = None
    nullspace_pinv_damping: float = 0.02
    compensate_gravity: bool = True
    compensate_coriolis: bool = True
    gains_frame: str = "world"
    pose_error_clip_m: float | None = None
    pose_error_clip_rad: float | None = None
    nullspace_torque_max_nm: float | None = None

    def __post_init__(self) -> None:
        for name in (
            "stiffness_translational_n_per_m",
            "stiffness_rotational_nm_per_rad",
            "damping_translational_ns_per_m",
            "damping_rotational_nms_per_rad",
        ):
            values = tuple(float(v) for v in getattr(self, name))
            check_len(name, values, 3)
            check_positive(name, values, allow_zero=True)
            object.__setattr__(self, name, values)
        k_n, d_n = self.nullspace_stiffness_nm_per_rad, self.nullspace_damping_nms_per_rad
        check_positive("nullspace_stiffness_nm_per_rad", k_n, allow_zero=True)
        if d_n is not None and not math.isfinite(d_n):
            raise InvalidArgumentError(
                f"invalid nullspace_damping_nms_per_rad {d_n!r}; valid: finite or None")
        check_positive("nullspace_pinv_damping", self.nullspace_pinv_damping)
        check_choice("impedance.gains_frame", self.gains_frame, FRAMES)
        for name in ("pose_error_clip_m", "pose_error_clip_rad", "nullspace_torque_max_nm"):
            check_optional_positive(name, getattr(self, name))

    @property
    def nullspace_damping(self) -> float:
        """Resolved null-space damping d_n [Nm s/rad] (2 sqrt(k_n) when unset)."""
        if self.nullspace_damping_nms_per_rad is None:
            return 2.0 * math.sqrt(self.nullspace_stiffness_nm_per_rad)
        return self.nullspace_damping_nms_per_rad
