"""Composed methods ``POLICY+CONTROLLER[@PRESET][+FLAG...]``: every shortcut is its composition,
bad parts are one line naming the choices, and a composed method gives its shortcut's rows."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
import pytest

from impact_control.errors import InvalidArgumentError
from impact_eval import methods
from impact_eval.cli import main
from impact_eval.method_parts import FLAGS, POLICY_FORMS
from impact_eval.methods import SHORTCUTS, compose, method_choices, resolve_method
from impact_eval.reproduce import parse_cells
from impact_eval.video import video_path


def _identity(spec: methods.MethodSpec) -> tuple:
    """Everything of a method but its name, description and factory object."""
    return (spec.policy, spec.controller, spec.preset, spec.action_mode, spec.observation,
            spec.robot, spec.settings_for("IMPACT/Hammer-v2"), spec.warm, spec.carry)


@pytest.mark.parametrize(("name", "composition"), [(n, c) for n, c, _ in SHORTCUTS])
def test_every_shortcut_is_its_composition(name: str, composition: str) -> None:
    shortcut, composed = resolve_method(name), resolve_method(composition)
    assert composed.name == composition and shortcut.name == name
    assert _identity(composed) == _identity(shortcut)
    assert composed.build.__qualname__ == shortcut.build.__qualname__


def test_the_docstring_table_lists_every_shortcut() -> None:
    rows = dict(re.findall(r"^\| `(\w+)` +\| `([^`]+)`", methods.__doc__, re.MULTILINE))
    assert rows == {name: composition for name, composition, _ in SHORTCUTS}


def test_parts_map_to_the_spec() -> None:
    spec = compose("dp.vanilla+impact@authors_sim+carry+commanded")
    assert (spec.controller, spec.preset, spec.carry, spec.warm) == \
        ("impact", "authors_sim", True, False)
    assert spec.robot is not None and spec.robot.torque_reading == "commanded"
    assert compose("dp.nominal+impact+warm").warm
    assert compose("dp.vanilla_rgb+impedance").observation is None  # its checkpoint's, per env
    assert compose("dp.my_run_3+impedance").policy == "dp.my_run_3"  # any checkpoint folder
    assert compose("scripted+impact").preset == "default"


@pytest.mark.parametrize(("name", "named"), [
    ("dp.vanilla+pid", "invalid controller 'pid'; valid choices: impedance, impact"),
    ("ppo+impact", f"invalid policy 'ppo'; valid choices: {', '.join(POLICY_FORMS)}"),
    ("dp.Vanilla+impact", "invalid policy 'dp.Vanilla'"),
    ("dp.vanilla+impact@papr", "invalid preset 'papr'; valid choices: default, paper"),
    ("dp.vanilla+impact+hot", f"invalid flag 'hot'; valid choices: {', '.join(FLAGS)}"),
    ("dp.vanilla+impact+warm+warm", "a flag repeats"),
    ("dp.vanilla+impact+warm+carry", "carry and warm exclude each other"),
    ("dp.vanilla+", "invalid controller ''"),
    ("scripted+impact@", "invalid preset ''; valid choices: default, paper"),  # issue 53
    ("dp.vanilla+impact@+carry", "invalid preset ''; valid choices: default, paper"),
    ("scripted+impedance+warm", "valid: warm on the impact controller"),
    ("dp.nominal+impedance@paper+warm", "the impedance controller does not have"),
])
def test_a_bad_composition_is_one_line_naming_the_choices(name: str, named: str) -> None:
    with pytest.raises(InvalidArgumentError) as info:
        resolve_method(name)
    assert "\n" not in str(info.value) and named in str(info.value)


def test_syntax_does_not_collide() -> None:
    assert all("+" not in n and "@" not in n for n, _, _ in SHORTCUTS)
    assert "POLICY+CONTROLLER[@PRESET][+FLAG...]" in method_choices()
    sb3 = resolve_method("sb3:runs/a+b@c.zip")  # the prefix wins: the path keeps + and @
    assert sb3.controller == "impact" and sb3.policy is None
    run_args = {"methods": ["dp.vanilla+impact@paper", "impact"], "values": [0.5]}
    assert parse_cells("dp.vanilla+impact@paper@0.5,impact@0.5", run_args) == \
        {("dp.vanilla+impact@paper", "0.5"), ("impact", "0.5")}
    a = video_path(Path("v"), "dp.vanilla+impact@paper", "m", "1", 0)
    assert a.parent.name == "dp.vanilla+impact@paper"


def test_a_composed_method_gives_its_shortcuts_rows(tmp_path: Path) -> None:
    """The acceptance, on the scripted expert (the DP version is the same code path): one
    sweep with both names; every column but ``method`` is equal, row by row."""
    out = tmp_path / "out"
    assert main(["--env", "IMPACT/Hammer-v1", "--method",
                 "scripted_impact_paper,scripted+impact@paper", "--masses", "2.5",
                 "--episodes", "2", "--workers", "1", "--out", str(out)]) == 0
    rows = pd.read_csv(out / "episodes.csv", dtype=str, keep_default_na=False)
    short = rows[rows["method"] == "scripted_impact_paper"].drop(columns="method")
    composed = rows[rows["method"] == "scripted+impact@paper"].drop(columns="method")
    assert len(short) == 2
    pd.testing.assert_frame_equal(short.reset_index(drop=True), composed.reset_index(drop=True))


@pytest.mark.parametrize(("method", "named"), [
    ("scripted+impact@",
     "invalid preset ''; valid choices: default, paper, keep_carried, lift_watch, "
     "authors_sim"),
    ("scripted+impedance+warm", "valid: warm on the impact controller"),
])
def test_an_empty_preset_or_a_cold_warm_flag_stops_the_cli_before_anything_is_written(
        tmp_path: Path, capsys: pytest.CaptureFixture, method: str, named: str) -> None:
    """Issue 53: neither means something else silently (``default``; a warm-up that warms
    nothing): one line, exit 2, no output directory."""
    from fixtures.eval_fake import ENV_ID

    code = main(["--env", ENV_ID, "--method", f"fake_fast,{method}", "--masses", "0.5",
                 "--episodes", "1", "--workers", "1", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and named in err and err.strip().count("\n") == 0
    assert not (tmp_path / "out").exists()
