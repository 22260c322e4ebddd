"""``experiments.demo_sink`` and ``experiments.contact_params`` (issue 55): bad input is one
line, exit 2, and nothing is written or overwritten."""

from __future__ import annotations

import pytest


@pytest.mark.parametrize(("argv", "message"), [
    (["--masses", "0.75,abc"], "invalid --masses '0.75,abc'"),
    (["--masses", "50"], "object_mass=50.0 out of range; valid: 0.05 to 12.0 kg"),
    (["--demos", "theirs"], "valid: a comma list of rebased, absolute, rebased_speed, "
                            "rebased_their_grasp"),
    (["--offset-kg", "0"], "invalid --offset-kg '0'; valid: a mass > 0 [kg] or privileged"),
    (["--offset-kg", "heavy"], "invalid --offset-kg 'heavy'"),
    (["--episodes", "0"], "--episodes and --workers must be >= 1"),
])
def test_demo_sink_refuses_bad_input_in_one_line(tmp_path, capsys, argv, message) -> None:
    from impact_experiments.demo_sink import main

    out = tmp_path / "rows.csv"
    with pytest.raises(SystemExit) as exit_:
        main([*argv, "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert exit_.value.code == 2 and "\n" not in err and message in err
    assert not out.exists()


def test_demo_sink_never_overwrites_rows(tmp_path, capsys) -> None:
    from impact_experiments.demo_sink import main

    out = tmp_path / "rows.csv"
    out.write_text("kept\n")
    with pytest.raises(SystemExit) as exit_:
        main(["--out", str(out)])
    assert exit_.value.code == 2 and "nothing is overwritten" in capsys.readouterr().err
    assert out.read_text() == "kept\n"


def test_contact_params_reads_the_pairs_and_refuses_an_env_without_a_hammer(capsys) -> None:
    from impact_experiments.contact_params import lines, main

    report = lines("IMPACT/HammerBasket-v1")
    assert report[0].startswith("noslip_iterations 1")
    pairs = [r for r in report if r.startswith("pair ")]
    assert len(pairs) == 4 and all("solref [0.02, 1.0]" in r for r in pairs)
    with pytest.raises(SystemExit) as exit_:
        main(["--env", "IMPACT/Dumbbell-v1"])
    err = capsys.readouterr().err.strip()
    assert exit_.value.code == 2 and "\n" not in err and "no body named hammer" in err


def test_demo_sink_builds_each_demonstrator_variant() -> None:
    """``rebased_speed`` steps 4 cm x 50/30, ``rebased_their_grasp`` grasps as theirs,
    ``privileged`` gives each episode its own mass as the offset."""
    from impact_envs.policies.authors_demonstrator import RebasedDemonstrator
    from impact_experiments.demo_sink import PRIVILEGED, _offset, _policy

    speed, theirs = _policy("rebased_speed"), _policy("rebased_their_grasp")
    assert isinstance(speed, RebasedDemonstrator) and speed.spec.max_step_m == pytest.approx(
        0.04 * 50 / 30)
    assert theirs.grasp_name == "theirs" and _policy("rebased").grasp_name == "ours"
    assert _offset(PRIVILEGED) == PRIVILEGED and _offset("0.6") == 0.6 and _offset("-1") is None


@pytest.mark.parametrize(("argv", "message"), [
    (["--table", "nowhere"], "has no episodes.csv"),
    (["--method", "nope"], "no rows of method 'nope' in bins '1.0'; valid methods: impact"),
    (["--bins", "x"], "invalid --bins 'x'"),
])
def test_policy_sink_refuses_bad_input_in_one_line(tmp_path, capsys, argv, message) -> None:
    import pandas as pd

    from impact_experiments.policy_sink import main

    table = tmp_path / "t"
    table.mkdir()
    pd.DataFrame([{"method": "impact", "env_id": "IMPACT/HammerBasket-v1", "param_value": 1.0,
                   "seed": 1, "episode": 0, "drawn_mass_kg": 1.5, "success": 0}]).to_csv(
        table / "episodes.csv", index=False)
    args = {"--table": str(table), "--method": "impact", "--bins": "1.0"}
    args.update(dict(zip(argv[::2], argv[1::2], strict=True)))
    out = tmp_path / "rows.csv"
    with pytest.raises(SystemExit) as exit_:
        main([*[x for kv in args.items() for x in kv], "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert exit_.value.code == 2 and "\n" not in err and message in err
    assert not out.exists()
