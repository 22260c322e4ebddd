"""The demo-ambiguity measure on synthetic stores: it must see when the demos' commands
depend on something the observations do not show (the mass), and not when they do not."""

from __future__ import annotations

import numpy as np

from impact_experiments.demo_ambiguity import OBS_KEYS, main
from impact_learn.dataset import EpisodeMeta, ReplayWriter

DIMS = {"ee_pos": 3, "ee_rot6d": 6, "gripper_width": 1, "object_pos": 3, "object_rot6d": 6,
        "goal_pos": 3}


def _store(path, overshoot_per_kg: float) -> None:
    """Ten identical lifts (object rising 0 -> 15 cm); the command leads the TCP by
    2 cm + ``overshoot_per_kg`` x mass."""
    writer = ReplayWriter(path, DIMS, {"env_id": "synthetic"})
    t = np.linspace(0.0, 1.0, 40)
    for e, mass in enumerate(np.linspace(0.1, 8.0, 10)):
        obs = {k: np.zeros((40, DIMS[k])) for k in OBS_KEYS}
        obs["object_pos"][:, 2] = 0.15 * t
        obs["ee_pos"][:, 2] = 0.15 * t + 0.005
        obs["gripper_width"][:, 0] = 0.02
        actions = np.zeros((40, 10))
        actions[:, 2] = obs["ee_pos"][:, 2] + 0.02 + overshoot_per_kg * mass
        actions[:, 9] = 1.0
        writer.append_episode(obs, actions, EpisodeMeta(float(mass), e, True, e))


def test_mass_dependent_commands_in_identical_states_are_reported(tmp_path, capsys):
    _store(tmp_path / "amb.zarr", overshoot_per_kg=0.02)
    main([str(tmp_path / "amb.zarr"), "--k", "3", "--light-kg", "0.5"])
    out = capsys.readouterr().out
    light = next(line for line in out.splitlines() if "light" in line)
    # the 0.1 kg demo commands 2.2 cm above the TCP; its neighbours (other masses, same
    # states) command more: light demos would be taught a heavier demo's overshoot
    assert "own median 2.2 cm" in light
    neighbours_cm = float(light.split("neighbours' ")[1].split(" cm")[0])
    assert neighbours_cm > 3.0


def test_mass_independent_commands_show_no_gap(tmp_path, capsys):
    _store(tmp_path / "same.zarr", overshoot_per_kg=0.0)
    main([str(tmp_path / "same.zarr"), "--k", "3"])
    light = next(line for line in capsys.readouterr().out.splitlines() if "light" in line)
    assert "own median 2.0 cm; their neighbours' 2.0 cm" in light
