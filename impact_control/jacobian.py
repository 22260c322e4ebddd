"""Regularized (damped) Jacobian pseudo-inverse shared by the estimator and null-space projector."""

from __future__ import annotations

import numpy as np

from impact_control import kernel_math


def regularized_wrench_map(
    jacobian: np.ndarray, damping: float, out: np.ndarray | None = None
) -> np.ndarray:
    """Return (J J^T + damping^2 I)^-1 J, i.e. (J^+)^T of the damped pseudo-inverse.

    Applied to a joint torque r (7,) it gives the regularized least-squares wrench
    argmin_w |J^T w - r|^2 + damping^2 |w|^2 (paper, "Estimating External Wrenches").
    J J^T + damping^2 I is symmetric positive definite for damping > 0, so the Cholesky solve
    (``kernel_math.regularized_wrench_map``) never meets a singular matrix.

    Args:
        jacobian: (6, 7) Jacobian.
        damping: lambda > 0 [units of J].
        out: Optional (6, 7) C-contiguous float64 output.

    Returns:
        (6, 7) map from joint torques to wrenches.
    """
    jac = np.ascontiguousarray(jacobian, dtype=np.float64)
    if out is None:
        out = np.empty_like(jac)
    gram = np.empty((jac.shape[0], jac.shape[0]))
    kernel_math.regularized_wrench_map(jac, float(damping) * float(damping), gram, out)
    return out
