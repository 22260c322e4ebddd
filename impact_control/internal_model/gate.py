"""Surprise gate with hysteresis (Schmitt trigger) deciding when the internal model learns."""

from __future__ import annotations

import numpy as np

from impact_control.internal_model.kernels import gate_update


class SurpriseGate:
    """Opens on large surprise while the slow wrench is quasi-steady; closes on small surprise.

    Paper: update "when surprise >= 5 N; slow-wrench rate <= 0.2", suspended "once the prediction
    error falls below the threshold". A single 5 N threshold would stop learning with up to 5 N of
    residual error (12 mm sag at 400 N/m), so the gate latches open until the surprise drops below
    ``release_threshold_n`` (release == open reproduces the literal single threshold).
    Learning additionally pauses (the gate stays latched) while the slow wrench is not
    quasi-steady, because w_slow is then still moving and is not a valid target. The logic is
    ``kernels.gate_update`` (also run inside ``controller_tick``).

    Attributes:
        open_threshold_n: Surprise that opens the gate [N].
        release_threshold_n: Surprise below which an open gate closes [N].
        slow_rate_max: Largest dimensionless slow-wrench rate counted as quasi-steady.
        is_open: Latched gate state (stored in ``state``, which the kernels update in place).
    """

    def __init__(
        self,
        open_threshold_n: float = 5.0,
        release_threshold_n: float = 0.5,
        slow_rate_max: float = 0.2,
        is_open: bool = False,
        state: np.ndarray | None = None,
    ) -> None:
        """Create a gate (closed unless ``is_open``).

        ``state``: optional float64 (1,) array holding the latched state (1.0 = open), e.g. a
        view into ``InternalModel``'s kernel buffer; a new array by default.
        """
        self.open_threshold_n = open_threshold_n
        self.release_threshold_n = release_threshold_n
        self.slow_rate_max = slow_rate_max
        self.state = np.zeros(1) if state is None else state
        self.state[0] = float(is_open)

    @property
    def is_open(self) -> bool:
        """Latched gate state."""
        return bool(self.state[0])

    @is_open.setter
    def is_open(self, value: bool) -> None:
        self.state[0] = float(value)

    def reset(self) -> None:
        """Close the gate."""
        self.state[0] = 0.0

    def update(self, surprise_n: float, slow_rate: float) -> bool:
        """Advance one tick; return True when the model should learn on this tick.

        Args:
            surprise_n: |w_pred - w_slow| over the (unmasked) force axes [N].
            slow_rate: Dimensionless slow-wrench rate (see ``SlowWrenchFilter.slow_rate``).
        """
        is_open, learn = gate_update(
            self.is_open, float(surprise_n), float(slow_rate),
            float(self.open_threshold_n), float(self.release_threshold_n),
            float(self.slow_rate_max),
        )  # fmt: skip
        self.is_open = is_open
        return bool(learn)
