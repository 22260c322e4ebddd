"""``--resume`` refuses rows written by other code (git sha, uncommitted changes) unless
``--allow-code-change``, and rows written with another checkpoint (its fingerprint)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from fixtures.eval_fake import sweep_args

from impact_control.errors import InvalidArgumentError
from impact_eval import runinfo
from impact_eval.checkpoints import fingerprint
from impact_eval.cli import main
from impact_eval.code_check import check_fingerprints, code_difference, recorded_git

SHA_A, SHA_B = "a" * 40, "b" * 40


def test_code_difference_names_what_changed() -> None:
    clean = {"sha": SHA_A, "dirty": False, "code_diff": None}
    assert code_difference(clean, clean) is None
    assert "commit aaaaaaaaaaaa" in code_difference(clean, {**clean, "sha": SHA_B})
    edited = {**clean, "dirty": True, "code_diff": "d1"}
    assert "uncommitted changes" in code_difference(clean, edited)
    assert code_difference(edited, edited) is None  # the same edit resumes
    assert "modified checkout" in code_difference({"sha": SHA_A, "dirty": True}, clean)
    assert code_difference({"sha": SHA_A, "dirty": False}, clean) is None  # older run.json
    assert code_difference({"sha": None}, clean) is None  # not in git: nothing to compare
    assert code_difference(None, clean) is None


def test_the_last_invocation_is_the_code_compared() -> None:
    run = {"git": {"sha": SHA_A}, "invocations": [{"git": {"sha": SHA_A}},
                                                  {"git": {"sha": SHA_B}}]}
    assert recorded_git(run)["sha"] == SHA_B
    assert recorded_git({"git": {"sha": SHA_A}})["sha"] == SHA_A
    assert recorded_git(None) is None


def test_a_fingerprint_covers_the_weights_not_the_stamp(tmp_path: Path) -> None:
    (tmp_path / "model.safetensors").write_bytes(b"\x01\x02")
    (tmp_path / "meta.json").write_text("{}")
    before = fingerprint(tmp_path)
    (tmp_path / "meta.json").write_text('{"evaluation": {}}')
    assert fingerprint(tmp_path) == before
    (tmp_path / "model.safetensors").write_bytes(b"\x01\x03")
    assert fingerprint(tmp_path) != before
    check_fingerprints({"m": before}, {"m": before, "new": None})  # extend adds methods
    check_fingerprints(None, {"m": before})  # recorded before fingerprints
    with pytest.raises(InvalidArgumentError, match="another checkpoint"):
        check_fingerprints({"m": before}, {"m": fingerprint(tmp_path)})


def _rewrite_git(out: Path, sha: str) -> None:
    path = out / runinfo.RUN_JSON
    run = json.loads(path.read_text())
    for record in (run, *run["invocations"]):
        record["git"] = {**record["git"], "sha": sha}
    path.write_text(json.dumps(run))


def test_resume_from_another_commit_is_refused_unless_allowed(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    if runinfo.git_state()["sha"] is None:
        pytest.skip("needs the package in a git checkout")
    out = tmp_path / "run"
    args = sweep_args(out, "--workers", "1", masses="0.5,2")
    assert main(args) == 0
    capsys.readouterr()
    _rewrite_git(out, SHA_A)
    assert main([*args, "--resume"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--allow-code-change" in err[0] and "aaaaaaaaaaaa" in err[0]
    assert main([*args, "--resume", "--allow-code-change"]) == 0
    last = json.loads((out / runinfo.RUN_JSON).read_text())["invocations"][-1]
    assert last["allow_code_change"] is True and last["git"]["sha"] != SHA_A
    assert main([*args, "--resume"]) == 0  # now the last rows' code is this checkout's
