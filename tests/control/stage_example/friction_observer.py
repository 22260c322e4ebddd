"""Joint-friction observer: an example stage (docs/adding_a_stage.md), not part of IMPACT.

It low-passes a viscous friction model plus the controller's own friction model and hands the
result to the wrench estimator, which subtracts it from the measured torque:

    tau_f[k+1] = tau_f[k] + alpha (tau_model[k] + b dq[k] - tau_f[k]),  alpha = dt / (T + dt)

tests/control/test_adding_a_stage.py copies the package, adds this module as
``impact_control/friction_observer.py`` and wires it in with the edits the guide shows
(``kernels.py``: one state field and two lines in the tick; ``controller.py``: build, reset,
hand over), then checks that snapshots and the kernel cache cover it with nothing else edited.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from impact_control.kernel_layout import Packed
from impact_control.stage_layout import Layout
from impact_control.validation import check_positive


@dataclass(frozen=True)
class FrictionObserverConfig:
    """Attributes:
        viscous_nm_s_per_rad: Viscous coefficient b of every joint [Nm s/rad].
        time_constant_s: Low-pass time constant T [s].
    """

    viscous_nm_s_per_rad: float = 0.5
    time_constant_s: float = 0.02

    def __post_init__(self) -> None:
        check_positive("viscous_nm_s_per_rad", self.viscous_nm_s_per_rad)
        check_positive("time_constant_s", self.time_constant_s)


class FrictionObserverScalars(NamedTuple):
    """The stage's constants: b [Nm s/rad] and the per-tick gain alpha."""

    viscous: float
    alpha: float


class FrictionObserverState(NamedTuple):
    """Everything ``friction_observer_step`` reads and writes.

    Attributes:
        params: ``FrictionObserverScalars``.
        tau_friction: The observed joint friction (7,) [Nm].
    """

    params: FrictionObserverScalars
    tau_friction: np.ndarray


FRICTION_OBSERVER_LAYOUT = Layout.of(FrictionObserverState, dict(tau_friction=7),
                                     args=("buf", "params"))
"""The stage's buffer (``params``, its scalars, pass through)."""
unpack_friction_observer = FRICTION_OBSERVER_LAYOUT.unpacker("unpack_friction_observer",
                                                             __name__)


def make_friction_observer_state(config: FrictionObserverConfig, dt_s: float) -> Packed:
    """``config`` at control period ``dt_s`` [s], packed."""
    sc = FrictionObserverScalars(config.viscous_nm_s_per_rad,
                                 dt_s / (config.time_constant_s + dt_s))
    return Packed(sc, np.zeros(FRICTION_OBSERVER_LAYOUT.size()))


@njit(cache=True, inline="always")
def friction_observer_step(dq, tau_model, st):
    """One tick; returns the observed friction (7,) [Nm] for the estimator."""
    par, tau = st.params, st.tau_friction
    for j in range(7):
        tau[j] += par.alpha * (tau_model[j] + par.viscous * dq[j] - tau[j])
    return tau


class FrictionObserver:
    """The stage's typed wrapper: ``packed`` (what the tick takes) and ``reset``."""

    def __init__(self, config: FrictionObserverConfig, dt_s: float) -> None:
        self.config = config
        self.packed = make_friction_observer_state(config, dt_s)
        self.state = unpack_friction_observer(self.packed.buffer, self.packed.scalars)[0]

    def reset(self) -> None:
        """Forget the observed friction."""
        self.state.tau_friction.fill(0.0)
