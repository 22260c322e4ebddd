"""``impact_experiments.hammer_basket_layout``: a seed's spawn is read by resetting the env,
and success is split by the spawn region."""

from __future__ import annotations

import gymnasium as gym
import pandas as pd

from impact_experiments.hammer_basket_layout import ENV_ID, main, spawns


def test_spawn_is_the_reset_of_that_seed() -> None:
    table = spawns(pd.Series([7, 3, 7]).to_numpy())
    assert list(table["seed"]) == [3, 7]
    env = gym.make(ENV_ID)
    obs, _ = env.reset(seed=7)
    row = table[table["seed"] == 7].iloc[0]
    assert row["hammer_x"] == float(obs["object_origin_pos"][0])
    assert row["basket_y"] == float(obs["goal_pos"][1])
    assert 0.25 <= row["hammer_x"] <= 0.40 and -0.40 <= row["hammer_y"] <= -0.20


def test_split_counts_every_episode_once(tmp_path, capsys) -> None:
    seeds = [1, 2, 3, 4]
    table = spawns(pd.Series(seeds).to_numpy())
    x_cut = float(table["hammer_x"].median())
    rows = [{"method": m, "seed": s, "success": int(s % 2 == 0 or m == "b")}
            for m in ("a", "b") for s in seeds]
    pd.DataFrame(rows).to_csv(tmp_path / "episodes.csv", index=False)
    main(["--table", str(tmp_path), "--x-below", f"{x_cut}", "--y-below", "0"])
    out = capsys.readouterr().out
    inside = int((table["hammer_x"] < x_cut).sum())
    line_b = next(line for line in out.splitlines() if line.startswith("| `b`"))
    assert f"{inside}/{inside} " in line_b and f"{4 - inside}/{4 - inside} " in line_b
    assert "episodes failed under every method: 0 of 4" in out


def test_a_folder_without_a_table_is_one_line(tmp_path, capsys) -> None:
    import pytest

    with pytest.raises(SystemExit) as exc:
        main(["--table", str(tmp_path)])
    assert exc.value.code == 2 and "no episodes.csv there" in capsys.readouterr().err
