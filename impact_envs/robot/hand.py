"""The simulated hands' grasp-force ranges, shared by ``RobotOptions``, the tasks and the
simulator.

Two hands, one finger mechanism (``fr3_hand.xml``: two slide joints on one tendon, a
position servo whose force range is the grasp force):

- ``"franka_hand"``: the Franka Hand. The quoted datasheet figures are 70 N continuous and
  140 N peak grasp force (docs/robot.md; unconfirmed, ../shared/reference/fr3.md);
  ``impact-robot pick-place --grasp-force-n`` uses the same 140 N bound. Every task but
  HammerBasket.
- ``"authors_sim"``: the fingers of the paper authors' simulation, PD servos that push with
  up to 200 N each (../shared/reference/authors_impact.md): beyond a real Franka Hand, used by
  ``IMPACT/HammerBasket-v1`` only, so that it is their benchmark (docs/hammer_basket.md).

No kernel reads this module (it is not part of the numba kernel digest).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real

from impact_control.errors import InvalidArgumentError, check_choice


@dataclass(frozen=True)
class HandSpec:
    """A simulated hand's grasp force: its default and largest accepted value [N]."""

    default_force_n: float
    max_force_n: float
    source: str


HANDS: dict[str, HandSpec] = {
    "franka_hand": HandSpec(70.0, 140.0, "the Franka Hand's peak grasp force"),
    "authors_sim": HandSpec(200.0, 200.0, "the authors' simulated fingers"),
}
"""The hands a task or ``RobotOptions(hand=...)`` may name."""

MAX_GRASP_FORCE_N = HANDS["franka_hand"].max_force_n
"""Largest grasp force [N] the simulated Franka Hand accepts (its quoted peak force)."""

DEFAULT_GRASP_FORCE_N = HANDS["franka_hand"].default_force_n
"""Default grasp force [N] of the Franka Hand (its quoted continuous force)."""


def check_hand(name: object) -> str:
    """``name`` if it is one of ``HANDS``, else a one-line ``InvalidArgumentError``."""
    check_choice("hand", name, tuple(HANDS))
    return str(name)


def check_grasp_force(value: object, hand: str = "franka_hand") -> None:
    """One-line ``InvalidArgumentError`` unless ``value`` is a real number (not a bool) above
    0 and at most ``hand``'s largest grasp force."""
    spec = HANDS[check_hand(hand)]
    if isinstance(value, bool) or not isinstance(value, Real) or not (
            math.isfinite(float(value)) and 0.0 < float(value) <= spec.max_force_n):
        raise InvalidArgumentError(
            f"invalid grasp_force_n {value!r}; valid: a number above 0 and at most "
            f"{spec.max_force_n:g} N ({spec.source}, hand {hand!r})")
