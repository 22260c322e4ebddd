"""Recording an evaluation in a checkpoint's meta.json."""

from __future__ import annotations

import json

import pytest

from impact_eval.stamp import main, stamp

HEADER = "method,env_id,param_name,param_value,seed,episode,success\n"


def _results(tmp_path):
    res = tmp_path / "res"
    res.mkdir()
    rows = [("augmented_dp", 0.1, 1), ("augmented_dp", 0.1, 0), ("augmented_dp", 2.5, 1),
            ("vanilla_dp", 0.1, 1)]
    (res / "episodes.csv").write_text(HEADER + "".join(
        f"{m},IMPACT/Hammer-v1,object_mass,{v},{i},{i},{s}\n" for i, (m, v, s) in enumerate(rows)))
    (res / "run.json").write_text(json.dumps({"git": {"sha": "abc"}}))
    ckpt = tmp_path / "ckpt"
    ckpt.mkdir()
    (ckpt / "meta.json").write_text(json.dumps({"train_step": 5}))
    return ckpt, res


def test_stamp_counts_successes_and_replaces_its_own_entry(tmp_path):
    ckpt, res = _results(tmp_path)
    stamp(ckpt, res, "augmented_dp")
    stamp(ckpt, res, "augmented_dp")
    meta = json.loads((ckpt / "meta.json").read_text())
    assert meta["train_step"] == 5
    assert len(meta["evaluation"]) == 1
    entry = meta["evaluation"][0]
    assert entry["success_episodes"] == {"0.1": [1, 2], "2.5": [1, 1]}
    assert entry["git"] == "abc" and entry["env_id"] == "IMPACT/Hammer-v1"


def test_stamp_unknown_method_is_one_line(tmp_path, capsys):
    ckpt, res = _results(tmp_path)
    with pytest.raises(SystemExit) as exc:
        main([str(ckpt), str(res), "--method", "impact"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "valid: augmented_dp, vanilla_dp" in err
