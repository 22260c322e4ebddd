"""``impact_experiments.demo_offsets``: the commanded-minus-measured TCP height of the
carried steps, per demo, read from a store."""

from __future__ import annotations

import numpy as np
import zarr

from impact_experiments.demo_offsets import main, offsets


def _store(path, demos: list[tuple[float, float, int]]) -> str:
    """A minimal store: per demo (mass, commanded offset while lifted, steps); the object is
    lifted 10 cm in the second half of each demo."""
    actions, ee, obj, ends, masses = [], [], [], [], []
    for mass, offset, steps in demos:
        z = np.full(steps, 0.3)
        lifted = np.arange(steps) >= steps // 2
        ee.append(np.c_[np.zeros((steps, 2)), z])
        act = np.zeros((steps, 10))
        act[:, 2] = z + np.where(lifted, offset, 0.0)
        actions.append(act)
        obj.append(np.c_[np.zeros((steps, 2)), 0.25 + 0.1 * lifted])
        ends.append(sum(len(a) for a in actions))
        masses.append(mass)
    root = zarr.open_group(str(path), mode="w")
    for name, value in (("data/action", actions), ("data/ee_pos", ee), ("data/object_pos", obj)):
        root.create_array(name, data=np.concatenate(value))
    root.create_array("meta/episode_ends", data=np.array(ends))
    root.create_array("meta/episode_param", data=np.array(masses))
    return str(path)


def test_offsets_are_the_carried_steps_medians(tmp_path) -> None:
    data = _store(tmp_path / "s.zarr", [(0.2, 0.005, 40), (0.9, 0.02, 60), (0.5, 0.0, 4)])
    mass, dz = offsets(data, lifted_m=0.05)
    assert mass.tolist() == [0.2, 0.9]  # the third lifted for only 2 steps
    np.testing.assert_allclose(dz, [0.005, 0.02])


def test_main_prints_one_line_per_band(tmp_path, capsys) -> None:
    data = _store(tmp_path / "s.zarr", [(0.2, 0.005, 40), (0.9, 0.02, 60)])
    assert main(["--data", data, "--bands", "2"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("2 demos") and len(lines) == 3
    assert "offset 0.50 cm" in lines[1] and "offset 2.00 cm" in lines[2]


def test_bad_input_is_one_line(tmp_path, capsys) -> None:
    import pytest

    for argv, says in ((["--data", str(tmp_path / "missing.zarr")], "does not exist"),
                       (["--data", _store(tmp_path / "s.zarr", [(0.2, 0.005, 40)]),
                         "--bands", "0"], "--bands must be >= 1")):
        with pytest.raises(SystemExit) as exc:
            main(argv)
        last = capsys.readouterr().err.strip().splitlines()[-1]
        assert exc.value.code == 2 and "error:" in last and says in last
    with pytest.raises(SystemExit):
        main(["--data", _store(tmp_path / "flat.zarr", [(0.2, 0.005, 4)])])  # nothing lifted
    assert "no demo lifted" in capsys.readouterr().err
