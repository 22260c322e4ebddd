"""The authors' demonstrator rebuilt (``policies/authors_demonstrator.py``, issue 55): targets
re-based on the measured TCP, their step and their offset, with hand-computed values."""

from __future__ import annotations

import numpy as np
import pytest

from impact_control.errors import InvalidArgumentError
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


def test_the_speed_mapping_scales_their_50_hz_step_to_our_rate() -> None:
    from impact_envs.policies.authors_demonstrator import rebased_spec

    assert rebased_spec("lead").max_step_m == 0.04
    assert rebased_spec("speed").max_step_m == pytest.approx(0.04 * 50.0 / 30.0)
    with pytest.raises(InvalidArgumentError, match="valid choices: lead, speed"):
        rebased_spec("fast")


def test_their_grasp_keeps_the_home_orientation_around_the_body_origin() -> None:
    """Theirs: yaw 0 in the hammer frame, the body origin's y; ours: square to the handle
    around its centreline (scripted_hammer_basket)."""
    theirs, ours = RebasedDemonstrator(grasp="theirs"), RebasedDemonstrator(grasp="ours")
    for demo in (theirs, ours):
        demo.reset(1)
        demo.act(_obs(np.array([0.3, 0.0, 0.6])))
    assert theirs.geometry.grasp_yaw_obj_rad == 0.0
    assert not np.allclose(theirs.rot[0], ours.rot[0])  # 6.9 deg apart
    assert ours.geometry.grasp_yaw_obj_rad != 0.0
    assert abs(theirs.grasp[0][1] - ours.grasp[0][1]) > 0.005  # the handle's centreline
    with pytest.raises(InvalidArgumentError, match="valid choices: ours, theirs"):
        RebasedDemonstrator(grasp="side")


def test_make_expert_builds_it_for_hammer_basket_only() -> None:
    from impact_envs.policies.authors_demonstrator import EXPERT_DEFAULTS
    from impact_envs.policies.experts import make_expert

    demo = make_expert("IMPACT/HammerBasket-v1", "privileged", expert="authors")
    assert isinstance(demo, RebasedDemonstrator) and demo.offset_mass_kg is None
    assert demo.grasp_name == EXPERT_DEFAULTS["grasp"]
    assert make_expert("hammer_basket", "none", expert="authors").offset_mass_kg == 0.0
    with pytest.raises(InvalidArgumentError, match="valid: privileged .*, none"):
        make_expert("IMPACT/HammerBasket-v1", "closed_loop", expert="authors")
    with pytest.raises(InvalidArgumentError, match="no expert 'authors' for task 'hammer'; "
                                                    "valid: scripted$"):
        make_expert("IMPACT/Hammer-v1", expert="authors")


def test_impact_collect_expert_authors_reaches_the_store_and_refuses_other_tasks(
        tmp_path, capsys) -> None:
    from impact_learn.collect import build_parser, config_from_args, main, store_attrs

    args = build_parser().parse_args(["--env", "IMPACT/HammerBasket-v1", "--out",
                                      str(tmp_path / "d.zarr"), "--expert", "authors",
                                      "--compensation", "privileged"])
    attrs = store_attrs(config_from_args(args), "object_mass")
    assert attrs["expert"] == {"name": "authors", "compensation": "privileged"}
    with pytest.raises(SystemExit) as exit_:
        main(["--env", "IMPACT/Hammer-v1", "--out", str(tmp_path / "e.zarr"),
              "--expert", "authors", "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert exit_.value.code == 2 and "\n" not in err and "valid: scripted" in err
    assert not (tmp_path / "e.zarr").exists()
