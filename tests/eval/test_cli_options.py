"""``cli_options``: every sweep field is declared once, and the generated parser, ``from_cli``
and ``to_argv`` agree with each other (issue 57 item 1)."""

from __future__ import annotations

from dataclasses import fields
from pathlib import Path

import pytest

from impact_control.errors import InvalidArgumentError
from impact_eval.cli_options import RESUME_RULES, Value, declared, option
from impact_eval.spec import RunOptions, SweepSpec
from impact_eval.sweep_command import sweep_parser


@pytest.mark.parametrize("cls", [SweepSpec, RunOptions])
def test_every_field_declares_its_command_line_form(cls: type) -> None:
    assert [f.name for f, _ in declared(cls)] == [f.name for f in fields(cls)]
    assert all(opt.resume in RESUME_RULES for _, opt in declared(cls))


def test_a_bad_resume_rule_is_refused_when_declared() -> None:
    with pytest.raises(ValueError, match="valid: same, grow, free"):
        option(Value("--x", "x"), default=0, resume="sometimes")


def test_the_parser_from_cli_and_to_argv_round_trip() -> None:
    spec = SweepSpec("IMPACT/Hammer-v1", ("impact", "vanilla_dp"), (0.5, 1.0), (1.0, 2.0),
                     episodes=7, seed=3, param="object_mass",
                     controller_overrides=("internal_model.slow_rate_max=1.5",),
                     robot_overrides=("realism=fr3",))
    argv = spec.to_argv()
    assert argv[:6] == ["--env", "IMPACT/Hammer-v1", "--method", "impact,vanilla_dp",
                        "--mass-bins", "0.5-1.0,1.0-2.0"]
    parsed = sweep_parser().parse_args([*argv, "--out", "x", "--workers", "1", "--resume"])
    assert SweepSpec.from_cli(parsed) == spec
    assert RunOptions.from_cli(parsed) == RunOptions(out=Path("x"), workers=1, resume=True)


def test_a_bad_value_is_one_line_from_the_declaration() -> None:
    parsed = sweep_parser().parse_args(["--env", "E", "--method", "a,,b", "--masses", "1"])
    with pytest.raises(InvalidArgumentError, match="malformed --method 'a,,b': empty item"):
        SweepSpec.from_cli(parsed)
    with pytest.raises(InvalidArgumentError, match="--episodes"):
        sweep_parser().parse_args(["--episodes", "many"])
