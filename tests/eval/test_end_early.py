"""``impact-eval --end-early``: an episode ends once its env's outcome has been settled for
``rollout.SETTLE_S`` (HammerBasket: the hammer let go and at rest inside their success box,
or off the table); elsewhere nothing changes."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
from fixtures.eval_fake import ENV_ID

from impact_eval.cli import main
from impact_eval.rollout import SETTLE_S


def _rows(out: Path) -> pd.DataFrame:
    return pd.read_csv(out / "episodes.csv", keep_default_na=False)


def test_a_placed_hammer_ends_the_episode_two_seconds_later(tmp_path: Path) -> None:
    """The scripted expert places a 0.3 kg hammer in the basket: the episode ends 2 s after
    the hammer came to rest there, long before the 1,800 steps, with the same success."""
    base = ["--env", "IMPACT/HammerBasket-v1", "--method", "scripted", "--masses", "0.3",
            "--episodes", "1", "--workers", "1", "--seed", "5"]
    assert main([*base, "--end-early", "--out", str(tmp_path / "early")]) == 0
    row = _rows(tmp_path / "early").iloc[0]
    assert row["success"] == 1 and row["failure_reason"] == ""
    assert SETTLE_S * 30 <= row["length"] < 1800
    assert row["time_to_success_s"] < row["length"] / 30 - SETTLE_S + 1e-9


def test_an_env_without_a_settled_outcome_runs_as_before(tmp_path: Path) -> None:
    base = ["--env", ENV_ID, "--method", "fake_fast", "--masses", "1,3", "--episodes", "2",
            "--workers", "1"]
    assert main([*base, "--out", str(tmp_path / "plain")]) == 0
    assert main([*base, "--end-early", "--out", str(tmp_path / "early")]) == 0
    assert (tmp_path / "plain" / "episodes.csv").read_bytes() == \
        (tmp_path / "early" / "episodes.csv").read_bytes()
