"""The authors' finger-hammer contact as an option on a compiled model (issue 55 item 6)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import impact_envs  # noqa: F401 - registers the envs
from impact_control.errors import InvalidArgumentError
from impact_envs.scenes_contact import (
    THEIR_PAIR_SOLIMP,
    THEIR_PAIR_SOLREF,
    finger_hammer_pairs,
    use_their_finger_contact,
)


def test_their_contact_is_the_mean_of_their_finger_and_hammer_geoms_and_survives_reset() -> None:
    assert pytest.approx((0.00125, 1.0)) == THEIR_PAIR_SOLREF
    assert pytest.approx((0.9745, 0.99495, 0.001)) == THEIR_PAIR_SOLIMP
    env = gym.make("IMPACT/HammerBasket-v1")
    m = env.unwrapped.sim.model
    pairs = finger_hammer_pairs(m)
    assert len(pairs) == 4 and m.opt.noslip_iterations == 1
    np.testing.assert_allclose(m.pair_solref[pairs], [[0.02, 1.0]] * 4)  # MuJoCo's defaults
    use_their_finger_contact(m)
    env.reset(seed=0, options={"object_mass": 5.0})
    m = env.unwrapped.sim.model
    np.testing.assert_allclose(m.pair_solref[pairs], [THEIR_PAIR_SOLREF] * 4)
    np.testing.assert_allclose(m.pair_solimp[pairs, :3], [THEIR_PAIR_SOLIMP] * 4)
    assert m.opt.noslip_iterations == 0
    env.close()


@pytest.mark.parametrize("env_id", ["IMPACT/Hammer-v1", "IMPACT/Dumbbell-v1"])
def test_a_scene_without_finger_hammer_pairs_is_refused_in_one_line(env_id: str) -> None:
    env = gym.make(env_id)
    with pytest.raises(InvalidArgumentError, match="no finger-pad/hammer contact pair; valid"):
        use_their_finger_contact(env.unwrapped.sim.model)
    env.close()


@pytest.mark.parametrize(("argv", "message"), [
    (["--mass-bin", "8"], "malformed --mass-bins '8': '8' is not LO-HI"),
    (["--mass-bin", "9-8"], "reversed or empty (LO < HI)"),
    (["--mass-bin", "1-2,2-3"], "valid: one LO-HI bin in kg"),
    (["--mass-bin", "8-50"], "out of range"),
    (["--method", "impact_authors"], "carries state across episodes"),
    (["--method", "nope"], "nope"),
])
def test_contact_paired_bad_input_is_one_line_and_writes_nothing(argv, message, tmp_path,
                                                                 capsys) -> None:
    from impact_experiments.contact_paired import main

    out = tmp_path / "x.csv"
    with pytest.raises(SystemExit) as exit_:
        main([*argv, "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert exit_.value.code == 2 and "\n" not in err and message in err
    assert not out.exists()
