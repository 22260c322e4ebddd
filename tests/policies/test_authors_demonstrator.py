"""The authors' demonstrator rebuilt (``policies/authors_demonstrator.py``, issue 55): targets
re-based on the measured TCP, their step and their offset, with hand-computed values."""

from __future__ import annotations

import numpy as np
import pytest

from impact_control.lie import rot6d_from_matrix
from impact_envs.policies.authors_demonstrator import APPROACH, LIFT, RebasedDemonstrator


def _obs(ee: np.ndarray) -> dict[str, np.ndarray]:
    return {"ee_pos": ee[None], "ee_rot6d": rot6d_from_matrix(np.eye(3))[None],
            "object_pos": np.array([[0.5, -0.3, 0.25]]),
            "object_rot6d": rot6d_from_matrix(np.eye(3))[None],
            "goal_pos": np.array([[0.35, 0.2, 0.235]])}


def test_a_step_is_re_based_on_the_measured_tcp_with_at_most_4_cm() -> None:
    demo = RebasedDemonstrator(offset_mass_kg=0.6)
    demo.reset(1)
    ee = np.array([0.3, 0.0, 0.6])
    action = demo.act(_obs(ee))[0]
    assert demo.phase[0] == APPROACH
    w = demo.waypoint(0, np.array([0.35, 0.2, 0.235]))
    expected = ee + 0.04 * (w - ee) / np.linalg.norm(w - ee)  # no offset before the grasp
    np.testing.assert_allclose(action[:3], expected, atol=1e-6)
    assert action[-1] < 0  # open


@pytest.mark.parametrize(("offset_kg", "mass_kg"), [(0.6, 9.0), (None, 1.5)])
def test_the_lift_adds_the_offset_of_its_mass_to_the_re_based_step(offset_kg, mass_kg) -> None:
    """Mass-blind (a fixed mass: what a Vanilla policy learns) or privileged (theirs)."""
    demo = RebasedDemonstrator(offset_mass_kg=offset_kg)
    demo.reset(1, np.array([mass_kg]))
    demo.act(_obs(np.array([0.3, 0.0, 0.6])))  # fixes the grasp point
    demo.phase[0], demo.steps[0] = LIFT, 0
    ee = demo.grasp[0] + np.array([0.0, 0.0, 0.01])  # 1 cm above the grasp point
    action = demo.act(_obs(ee))[0]
    w = demo.waypoint(0, np.array([0.35, 0.2, 0.235]))
    offset = (0.6 if offset_kg is not None else mass_kg) * 9.81 / 400.0
    expected = ee + 0.04 * (w - ee) / np.linalg.norm(w - ee) + [0.0, 0.0, offset]
    np.testing.assert_allclose(action[:3], expected, atol=1e-6)
    assert action[-1] > 0  # closed
