"""Grasped-load set-down (``impact_experiments/press_setdown.py``, issue 37 item 4): the
measure on a synthetic trace, one short physical case (3 kg, 15 mm, 3 s carry, 2 s hold;
impedance and the shipped ``default``), resume and traces with a fake run, and the CLI's
one-line errors."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from impact_control.errors import InvalidArgumentError
from impact_experiments import press, press_setdown
from impact_experiments.press_setdown import moving_mean, press_measure, setdown

K_N_PER_M = 400.0  # the translational stiffness of both presets


def test_moving_mean_and_press_measure_by_hand() -> None:
    """dt 10 ms: 50 ms = 5 samples, the press read from 1 s (sample 100) to the end."""
    assert np.allclose(moving_mean(np.array([1.0, 2.0, 3.0, 4.0]), 2), [1.5, 2.5, 3.5])
    force = np.full(300, 10.0)
    force[50] = 1000.0  # before 1 s: not part of the press
    force[150:153] = 40.0  # a 30 ms bump: a 5-sample window holds it and two 10 N samples
    press_n, last = press_measure(force, 0.01)
    assert press_n == pytest.approx((3 * 40.0 + 2 * 10.0) / 5)
    assert last == pytest.approx(10.0)
    force[100] = 60.0  # the first window that counts starts at 1 s: (60 + 4 x 10) / 5 = 20
    force[150:153] = 10.0
    assert press_measure(force, 0.01)[0] == pytest.approx(20.0)


@pytest.fixture(scope="module")
def short_case() -> dict[str, dict]:
    """3 kg set down 15 mm below the table contact, 3 s carry, 2 s hold, seed 0."""
    return {mode: setdown(mode, 3.0, 0.015, 2.0, seed=0, carry_s=3.0)[0]
            for mode in ("impedance", "impact")}


def test_load_is_carried_before_the_set_down(short_case: dict[str, dict]) -> None:
    """No table contact while carried; impedance sags by about m g / K (78 mm measured, 74 mm
    from m g / K alone), IMPACT feeds the weight forward (30.4 N measured) and stays on its
    target; the load does not slip in the fingers (0.4-0.6 mm of pad compliance measured)."""
    imp, dft = short_case["impedance"], short_case["impact"]
    weight = imp["weight_n"]
    assert weight == pytest.approx(3.0 * 9.81)
    for row in (imp, dft):
        assert row["carried_table_max_n"] == 0.0 and row["hand_table_max_n"] == 0.0
        assert row["max_slip_mm"] < 2.0
    assert imp["carry_sag_mm"] == pytest.approx(1e3 * weight / K_N_PER_M, abs=10.0)
    assert dft["carry_ff_z_n"] == pytest.approx(weight, abs=3.0)
    assert abs(dft["carry_sag_mm"]) < 5.0


def test_table_takes_the_load_after_the_set_down(short_case: dict[str, dict]) -> None:
    """Impedance: the table carries the weight plus K x depth (35.9 N measured, 35.4 N
    expected; joint friction takes up to 4 N in these runs). IMPACT still holds part of the
    weight up after 2 s (final feedforward 12.7 N): the table takes m g + K x depth less
    that; both stay within impedance's press + 3 N."""
    imp, dft = short_case["impedance"], short_case["impact"]
    expected = imp["weight_n"] + K_N_PER_M * 0.015
    assert imp["last_s_mean_n"] >= imp["weight_n"] - 1.0
    assert imp["last_s_mean_n"] == pytest.approx(expected, abs=4.0)
    assert dft["last_s_mean_n"] + dft["final_ff_z_n"] == pytest.approx(expected, abs=6.0)
    assert dft["last_s_mean_n"] >= K_N_PER_M * 0.015 - 1.0
    assert dft["press_n"] <= imp["press_n"] + press_setdown.BOUND_N


def _fake_setdown(calls: list) -> object:
    def fake(mode: str, load_kg: float, depth_m: float, hold_s: float,
             seed: int, robot: object = None) -> tuple[dict, pd.DataFrame]:
        calls.append(mode)
        row = {c: 0.0 for c in press_setdown.COLUMNS}
        row.update(mode=mode, load_kg=load_kg, depth_mm=1e3 * depth_m, hold_s=hold_s,
                   seed=seed, holds=0, press_n=40.0 if mode == "impact" else 30.0,
                   press_over_impedance_n=math.nan)
        return row, pd.DataFrame({"t_s": [0.01], "load_table_n": [1.0]})
    return fake


def test_rows_append_resume_and_failing_trace(tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    """Rows are appended as they finish; a rerun skips them; the finished file compares with
    impedance; the failing ``impact`` row (40 N > 30 + 3 N) leaves a trace."""
    calls: list[str] = []
    monkeypatch.setattr(press_setdown, "setdown", _fake_setdown(calls))
    args = (["impedance", "impact"], [3.0], [15.0], 6.0, 0)
    df = press_setdown.run_setdown(tmp_path, *args)
    assert calls == ["impedance", "impact"]
    assert list(df["press_over_impedance_n"]) == [0.0, 10.0]
    assert (tmp_path / "setdown_traces" / "impact_3kg_15mm.csv").exists()
    assert not (tmp_path / "setdown_traces" / "impedance_3kg_15mm.csv").exists()
    with (tmp_path / "setdown.csv").open("a") as f:
        f.write("impact_unguarded,3.0,15.0,6.0,0,29.4,5")  # a crash mid-row
    again = press_setdown.run_setdown(tmp_path, *args)
    assert calls == ["impedance", "impact"]  # nothing rerun; the cut row dropped
    pd.testing.assert_frame_equal(again.reset_index(drop=True), df.reset_index(drop=True))
    saved = pd.read_csv(tmp_path / "setdown.csv")
    assert list(saved.columns) == list(press_setdown.COLUMNS) and len(saved) == 2


@pytest.mark.parametrize(("flags", "message"), [
    (["--loads-kg", "3,x"], "valid: comma-separated numbers in (0, 10] kg"),
    (["--loads-kg", "0"], "invalid --loads-kg '0'"),
    (["--setdown-depths", "15,-1"], "valid: comma-separated numbers in (0, 100] mm"),
    (["--modes", "impact,nope"], "valid: impedance, impact, impact_unguarded, paper, "
                                 "authors_sim"),
    (["--scenario", "setdown", "--hold-s", "1"], "valid: 2 to 60 s for the set-down"),
    (["--scenario", "wall"], "invalid choice: 'wall'"),
    (["--traces", "some"], "invalid choice: 'some'"),
    (["--robot-set", "realism=mars"], "valid choices: ideal, fr3"),
    (["--robot-set", "nope=1"], "valid: FIELD=VALUE with FIELD one of"),
])
def test_bad_flags_are_one_line(flags: list[str], message: str,
                                capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        press.main(flags)
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1 and message in err


def test_authors_sim_mode_runs_the_shipped_preset() -> None:
    """``authors_sim`` is the preset as shipped, in the controller's "impact" mode."""
    from impact_control.presets import preset_config

    assert press.mode_controller("authors_sim") == ("impact", preset_config("authors_sim"))


def test_other_columns_are_refused_in_one_line(tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    """A ``setdown.csv`` written with other columns is not appended to."""
    (tmp_path / "setdown.csv").write_text("mode,press_n\nimpact,1.0\n")
    with pytest.raises(SystemExit) as exc:
        press.main(["--scenario", "setdown", "--out", str(tmp_path)])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1 and "other columns" in err


def test_a_resume_with_another_robot_is_refused(tmp_path: Path,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    """The set-down's robot goes to ``robot.json`` and reaches every run; rows of one robot
    are not resumed under another (a directory without the file holds the ideal robot's)."""
    calls: list[str] = []
    monkeypatch.setattr(press_setdown, "setdown", _fake_setdown(calls))
    args = (["impedance"], [3.0], [15.0], 6.0, 0)
    press_setdown.run_setdown(tmp_path, *args)
    (tmp_path / "robot.json").unlink()  # as results/press, written before the option
    with pytest.raises(InvalidArgumentError, match="--robot-set none .ideal., not"):
        press_setdown.run_setdown(tmp_path, *args, robot_set=("realism=fr3",))
    press_setdown.run_setdown(tmp_path / "fr3", *args, robot_set=("realism=fr3",))
    with pytest.raises(InvalidArgumentError, match=r"\['realism=fr3'\], not none"):
        press_setdown.run_setdown(tmp_path / "fr3", *args)
    assert calls == ["impedance", "impedance"]


def test_the_set_down_robot_takes_the_profile() -> None:
    """Under ``realism=fr3`` the set-down's controller model is the profile's perturbed one
    and its grip stays the set-down's 140 N; the ideal robot's model is the plant's."""
    ideal = press_setdown.setdown_rig("impact", 3.0, 0)
    fr3 = press_setdown.setdown_rig("impact", 3.0, 0, press_setdown.setdown_robot(["realism=fr3"]))
    q = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    for rig in (ideal, fr3):
        rig.arm.update(q, np.zeros(7))
    assert not np.allclose(ideal.arm.gravity, fr3.arm.gravity, atol=1e-3)
    assert press_setdown.setdown_robot(["realism=fr3"]).grasp_force_n == press_setdown.GRASP_FORCE_N
