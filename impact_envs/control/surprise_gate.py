"""Surprise gate with hysteresis (Schmitt trigger) deciding when the internal model learns."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class SurpriseGate:
    """Opens on large surprise while the slow wrench is quasi-steady; closes on small surprise.

    Paper: update "when surprise >= 5 N; slow-wrench rate <= 0.2", suspended "once the prediction
    error falls below the threshold". A single 5 N threshold would stop learning with up to 5 N of
    residual error (12 mm sag at 400 N/m), so the gate latches open until the surprise drops below
    ``release_threshold_n`` (release == open reproduces the literal single threshold).
    Learning additionally pauses (the gate stays latched) while the slow wrench is not
    quasi-steady, because w_slow is then still moving and is not a valid target.

    Attributes:
        open_threshold_n: Surprise that opens the gate [N].
        release_threshold_n: Surprise below which an open gate closes [N].
        slow_rate_max: Largest dimensionless slow-wrench rate counted as quasi-steady.
        is_open: Latched gate state.
    """

    open_threshold_n: float = 5.0
    release_threshold_n: float = 0.5
    slow_rate_max: float = 0.2
    is_open: bool = False

    def reset(self) -> None:
        """Close the gate."""
        self.is_open = False

    def update(self, surprise_n: float, slow_rate: float) -> bool:
        """Advance one tick; return True when the model should learn on this tick.

        Args:
            surprise_n: |w_pred - w_slow| over the (unmasked) force axes [N].
            slow_rate: Dimensionless slow-wrench rate (see ``SlowWrenchFilter.slow_rate``).
        """
        quasi_steady = slow_rate <= self.slow_rate_max
        if self.is_open:
            if surprise_n < self.release_threshold_n:
                self.is_open = False
        elif surprise_n >= self.open_threshold_n and quasi_steady:
            self.is_open = True
        return self.is_open and quasi_steady
