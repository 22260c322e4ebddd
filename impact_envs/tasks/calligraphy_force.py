"""Explicit normal-force command of the calligraphy task (hybrid position–force control).

While the pen is pressed, the commanded wrench (robot-on-environment sign, world frame) is

    w_cmd = (0, 0, −F(t), 0, 0, 0)

with ``F(t)`` ramping from 0 to ``force_n`` at ``ramp_n_per_s`` after contact is engaged (a
gentle landing instead of a 15 N step while the tip may still be a few mm above the paper).
The command comes with a learning mask that freezes the three force axes: the normal force
is commanded, and the tangential force while writing is the paper's friction drag caused by
that press (μ F ≈ 4.5 N), which reverses with every change of stroke direction; neither is a
load to learn. The controller then neither learns these forces nor lets its feedforward on a
frozen axis follow the model's prediction: it holds the feedforward of the last unmasked tick
(the tool weight learned in free air), because the prediction follows input features that
pressing changes (the estimated wrench moves by −F), which would feed the pressing force back
into itself. Torques stay learnable.

The env passes the returned array to every control tick of the policy step, and ``tick`` runs
before each of them (``Task.before_tick``), so the ramp acts at 1 kHz.
"""

from __future__ import annotations

import numpy as np

PRESS_LEARN_MASK = np.array([False, False, False, True, True, True])
"""Internal-model learning mask while pressing: the force axes frozen (their feedforward held
by the controller). Until 2026-11-24 only z was frozen; with the ``default`` controller preset,
which learns ten times faster, the model then chased the direction-dependent drag and the
expert's stroke error grew from 3.0 to 5.7 mm (docs/envs.md)."""


class NormalForceCommand:
    """Ramped pressing force along −z.

    Args:
        force_n: desired normal force [N] (the robot pushes down with it).
        ramp_n_per_s: rate at which the force builds up after engaging [N/s].
    """

    def __init__(self, force_n: float, ramp_n_per_s: float = 60.0) -> None:
        self.force_n = float(force_n)
        self.ramp_n_per_s = float(ramp_n_per_s)
        self.wrench = np.zeros(6)
        self.reset()

    def reset(self) -> None:
        """Forget the episode: not pressing."""
        self.engaged = False
        self.level_n = 0.0
        self.wrench[:] = 0.0

    def engage(self) -> tuple[np.ndarray, np.ndarray]:
        """Press (idempotent); returns the live command array and the learning mask."""
        if not self.engaged:
            self.engaged = True
            self.level_n = 0.0
        self._update(0.0)
        return self.wrench, PRESS_LEARN_MASK

    def release(self) -> None:
        """Stop pressing."""
        self.engaged = False
        self.level_n = 0.0
        self.wrench[:] = 0.0

    def tick(self, dt_s: float) -> None:
        """Per control tick: ramp while engaged.

        Args:
            dt_s: control period [s].
        """
        if self.engaged:
            self._update(dt_s)

    def _update(self, dt_s: float) -> None:
        self.level_n = min(self.force_n, self.level_n + self.ramp_n_per_s * dt_s)
        self.wrench[2] = -self.level_n
