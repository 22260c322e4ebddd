"""Physics acceptance checks of the closed loop (known wrench recovery, payload sag)."""

from __future__ import annotations

import pytest

from impact_experiments.physics import noise_floor, payload_hold, wrench_recovery


@pytest.mark.parametrize("estimator", ["residual", "momentum"])
def test_known_wrench_recovered_by_slow_estimate_with_noise(estimator):
    rows = wrench_recovery(estimator, n_poses=2, seed=3)
    for r in rows:
        assert r["force_err_n"] < 1.0, r
        assert r["torque_err_nm"] < 0.1, r


def test_payload_sag_impedance_vs_impact():
    mass = 5.0
    imp = payload_hold("impedance", mass_kg=mass, hold_s=5.0)
    # plain impedance sags by about m g / K (400 N/m) -> 12.3 cm; friction and the wrist
    # rotation under the load add a little
    assert imp["final_sag_m"] == pytest.approx(mass * 9.81 / 400.0, rel=0.15)
    ff = payload_hold("impact", mass_kg=mass, hold_s=5.0)
    assert abs(ff["final_sag_m"]) < 3e-3
    assert ff["settle_3mm_s"] < 4.5
    # the full error also holds the Coulomb-friction dead-band (a few mm), never the load
    assert ff["final_error_m"] < 0.015


def test_noise_floor_removes_each_pose_s_bias():
    """Under ``realism="fr3"`` each pose carries its own ~1 N offset (docs/sensing.md); the
    noise floor removes each pose's mean, so what is left is the sensors' white noise and the
    drift, not the offsets' spread between poses (1.27 N when one mean was removed)."""
    from impact_envs.envs.options import RobotOptions

    floor = noise_floor(n_poses=2, seed=5, measure_s=0.5, robot=RobotOptions(realism="fr3"))
    assert 0.0 < floor["raw_std_n"] < 0.3
    assert floor["slow_std_n"] < floor["raw_std_n"]
