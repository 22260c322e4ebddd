"""Explicit normal-force command of the calligraphy task (hybrid position–force control).

While the pen is pressed, the commanded wrench (robot-on-environment sign, world frame) is

    w_cmd = (0, 0, −F(t) − (w_ff,z(t) − w_ff,z(t_free)), 0, 0, 0)

- ``F(t)`` ramps from 0 to ``force_n`` at ``ramp_n_per_s`` after contact is engaged (a gentle
  landing instead of a 15 N step while the tip may still be a few mm above the paper);
- ``w_ff,z(t_free)`` is IMPACT's applied feedforward at the last tick the tip was in free
  air. The learn mask freezes the normal axis, so the internal model never *learns* the
  pressing force, but its prediction still follows its input features (the estimated wrench
  is one of them, and pressing changes it by −F): a learned 9.3 N tool weight was predicted as
  2–4 N while pressing, i.e. positive feedback through the features. Holding the applied
  normal feedforward at its free-air value (the tool weight) cancels that drift; under plain
  impedance the feedforward is 0 and so is the correction.

The env passes the returned array to every control tick of the policy step, and ``tick`` runs
before each of them (``Task.before_tick``), so ramp and hold act at 1 kHz.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

PRESS_LEARN_MASK = np.array([True, True, False, True, True, True])
"""Internal-model learning mask while pressing: the normal (z) axis frozen."""


class NormalForceCommand:
    """Ramped pressing force along −z with the normal feedforward held at its free-air value.

    Args:
        force_n: desired normal force [N] (the robot pushes down with it).
        ramp_n_per_s: rate at which the force builds up after engaging [N/s].
        free_air_m: the tip counts as in free air above this height over the surface [m].
    """

    def __init__(self, force_n: float, ramp_n_per_s: float = 60.0,
                 free_air_m: float = 0.005) -> None:
        self.force_n = float(force_n)
        self.ramp_n_per_s = float(ramp_n_per_s)
        self.free_air_m = float(free_air_m)
        self.ff_source: Callable[[], np.ndarray] | None = None
        self.wrench = np.zeros(6)
        self.reset()

    def reset(self) -> None:
        """Forget the episode: not pressing, no free-air feedforward recorded."""
        self.engaged = False
        self.level_n = 0.0
        self.free_ff_z: float | None = None
        self.hold_ff_z = 0.0
        self.wrench[:] = 0.0

    def _ff_z(self) -> float:
        return 0.0 if self.ff_source is None else float(self.ff_source()[2])

    def engage(self) -> tuple[np.ndarray, np.ndarray]:
        """Press (idempotent); returns the live command array and the learning mask."""
        if not self.engaged:
            self.engaged = True
            self.level_n = 0.0
            self.hold_ff_z = self._ff_z() if self.free_ff_z is None else self.free_ff_z
        self._update(0.0)
        return self.wrench, PRESS_LEARN_MASK

    def release(self) -> None:
        """Stop pressing."""
        self.engaged = False
        self.level_n = 0.0
        self.wrench[:] = 0.0

    def tick(self, tip_height_m: float, dt_s: float) -> None:
        """Per control tick: ramp and hold while engaged, else record the free-air feedforward.

        Args:
            tip_height_m: pen-tip height above the writing surface [m].
            dt_s: control period [s].
        """
        if self.engaged:
            self._update(dt_s)
        elif tip_height_m > self.free_air_m:
            self.free_ff_z = self._ff_z()

    def _update(self, dt_s: float) -> None:
        self.level_n = min(self.force_n, self.level_n + self.ramp_n_per_s * dt_s)
        self.wrench[2] = -self.level_n - (self._ff_z() - self.hold_ff_z)
