"""Regularized (damped) Jacobian pseudo-inverse shared by the estimator and null-space projector."""

from __future__ import annotations

import numpy as np

try:  # The raw LAPACK gufunc skips np.linalg.solve's errstate set-up (~5 us per call at 1 kHz).
    from numpy.linalg._umath_linalg import solve as _solve_gufunc
except ImportError:  # pragma: no cover - other NumPy layouts
    _solve_gufunc = np.linalg.solve


def regularized_wrench_map(
    jacobian: np.ndarray, damping: float, out: np.ndarray | None = None
) -> np.ndarray:
    """Return (J J^T + damping^2 I)^-1 J, i.e. (J^+)^T of the damped pseudo-inverse.

    Applied to a joint torque r (7,) it gives the regularized least-squares wrench
    argmin_w |J^T w - r|^2 + damping^2 |w|^2 (paper, "Estimating External Wrenches").
    J J^T + damping^2 I is symmetric positive definite for damping > 0, so the solve never
    meets a singular matrix.

    Args:
        jacobian: (6, 7) Jacobian.
        damping: lambda > 0 [units of J].
        out: Optional (6, 7) output.

    Returns:
        (6, 7) map from joint torques to wrenches.
    """
    gram = jacobian @ jacobian.T
    gram.flat[:: gram.shape[0] + 1] += damping * damping
    sol = _solve_gufunc(gram, jacobian)
    if out is None:
        return sol
    out[:] = sol
    return out


class RegularizedWrenchMap:
    """Preallocated per-tick version of ``regularized_wrench_map`` for a fixed damping.

    Attributes:
        matrix: The last (J J^T + damping^2 I)^-1 J (6, 7), overwritten by ``update``.
    """

    def __init__(self, damping: float, n_joints: int = 7) -> None:
        """Allocate buffers for a (6, n_joints) Jacobian and damping lambda > 0."""
        self.damping = damping
        self.matrix = np.zeros((6, n_joints))
        self._gram = np.zeros((6, 6))
        self._reg = np.eye(6) * damping * damping

    def update(self, jacobian: np.ndarray) -> np.ndarray:
        """Recompute and return ``matrix`` for ``jacobian`` (6, n_joints)."""
        np.dot(jacobian, jacobian.T, out=self._gram)
        self._gram += self._reg
        _solve_gufunc(self._gram, jacobian, out=self.matrix)
        return self.matrix
