"""``impact-bench --episode`` (issue 56 item 1): a camera policy's episode split into physics,
controller, rendering and policy, per variant (what it prints, never how fast)."""

from __future__ import annotations

import pytest


def test_bench_prints_the_episode_split(capsys) -> None:
    from impact_eval import bench

    bench.main(["--steps", "9", "--repeat", "1", "--episode", "--image-size", "16"])
    out = capsys.readouterr().out
    assert "one camera-policy episode (overview, wrist, 16x16 px, 750 policy steps)" in out
    for row in ("shadows, every frame", "shadows, frames read only",
                "no shadows, every frame", "no shadows, frames read only"):
        assert row in out
    assert "physics (raw mj_step)" in out and "vs raw mj_step" in out


@pytest.mark.parametrize(("flags", "message"), [
    (["--cameras", "nope"], "invalid camera 'nope'; valid choices:"),
    (["--horizon", "5"], "horizon 5 must be divisible by 4"),
    (["--action-steps", "40"], "n_action_steps must be <= horizon"),
])
def test_bad_episode_flags_are_one_line_before_anything_runs(flags, message, capsys) -> None:
    from impact_eval import bench

    with pytest.raises(SystemExit) as info:
        bench.main(["--steps", "2", "--repeat", "1", "--episode", *flags])
    err = capsys.readouterr().err.strip().splitlines()
    assert info.value.code == 2 and len(err) == 1 and message in err[0]
