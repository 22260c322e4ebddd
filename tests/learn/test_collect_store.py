"""Where ``impact-collect`` writes (``impact_learn/collect_store.py``): an unwritable ``--out``
is one line, an ``OUT.partial`` that is not a store of ours is refused and kept, and
``--resume`` checks every chunk of the store before appending (a damaged one is refused and
left as it was)."""

from __future__ import annotations

import numpy as np
import pytest
import zarr
from fixtures.fake_reach import FAKE_ID, FakeExpert, collect_demos
from fixtures.tiny_store import chunk_file, snapshot

from impact_control.errors import InvalidArgumentError
from impact_learn import collect as collect_module
from impact_learn.dataset import load_replay
from impact_learn.store_format import CHECKSUM_ATTR


def _cli(argv: list[str], monkeypatch, capsys) -> tuple[int, str]:  # noqa: ANN001
    monkeypatch.setattr(collect_module, "default_expert_factory", lambda cfg: FakeExpert)
    try:
        collect_module.main(["--env", FAKE_ID, "--episodes", "2", "--n-envs", "2",
                             "--no-progress", *argv])
        code = 0
    except SystemExit as exc:
        code = int(exc.code or 0)
    return code, capsys.readouterr().err


@pytest.mark.parametrize("out", ["/proc/impact-collect-test/x.zarr", "{tmp}/afile/x.zarr",
                                 "{tmp}/afile/deeper/x.zarr"])
def test_an_unwritable_out_is_one_line(tmp_path, monkeypatch, capsys, out):
    (tmp_path / "afile").write_text("x")
    before = snapshot(tmp_path)
    code, err = _cli(["--out", out.replace("{tmp}", str(tmp_path))], monkeypatch, capsys)
    assert code == 2 and err.count("\n") == 1 and "cannot write" in err, err
    assert "Traceback" not in err and snapshot(tmp_path) == before
    assert not (tmp_path / "afile").is_dir()


@pytest.mark.parametrize("kind", ["folder with a file", "file", "foreign zarr group"])
def test_a_partial_that_is_not_ours_is_refused_and_kept(tmp_path, kind):
    partial = collect_module.partial_path(tmp_path / "d.zarr")
    if kind == "folder with a file":
        partial.mkdir()
        (partial / "notes.txt").write_text("mine")
    elif kind == "file":
        partial.write_text("mine")
    else:
        zarr.open_group(str(partial), mode="w").create_array("x", shape=(3,), dtype="f4")[:] = 1
    before = snapshot(tmp_path)
    with pytest.raises(InvalidArgumentError, match="is not a store of an unfinished"):
        collect_demos(tmp_path / "d.zarr", param=0.2)
    assert snapshot(tmp_path) == before


def test_a_partial_torn_at_creation_is_replaced(tmp_path):
    partial = collect_module.partial_path(tmp_path / "d.zarr")
    (partial / "data").mkdir(parents=True)
    (partial / "zarr.json").write_text("{\"zarr_format\": 3, \"node_")  # torn metadata only
    assert collect_demos(tmp_path / "d.zarr", param=0.2) == 6


@pytest.fixture
def three(tmp_path):
    """A finished store of 3 fake-reach demos (``--resume`` to 6 continues it)."""
    collect_demos(tmp_path / "d.zarr", param_list=(0.2, 3.0), episodes=3)
    return tmp_path / "d.zarr"


@pytest.mark.parametrize("target", ["data/ee_pos", "data/goal_pos", "meta/episode_seed"])
@pytest.mark.parametrize("where", ["finished", "partial"])
def test_resume_refuses_a_deleted_chunk_and_changes_nothing(three, target, where):
    store = three
    if where == "partial":
        store = collect_module.partial_path(three)
        three.rename(store)
    chunk_file(store, target, 0).unlink()
    before = snapshot(store.parent)
    with pytest.raises(InvalidArgumentError) as err:
        collect_demos(three, param_list=(0.2, 3.0), resume=True)
    assert "cannot resume" in str(err.value) and target in str(err.value)
    assert snapshot(store.parent) == before


def test_resume_cli_on_a_damaged_store_exits_2(three, monkeypatch, capsys):
    chunk_file(three, "data/action", 0).write_bytes(b"\x00torn")
    code, err = _cli(["--out", str(three), "--mass-list", "0.2,3", "--episodes", "6",
                      "--n-envs", "4", "--resume"], monkeypatch, capsys)
    assert code == 2 and err.count("\n") == 1 and "data/action" in err, err


def test_resume_of_a_store_without_checksums_adds_them(three, tmp_path):
    zarr.open_group(str(three), mode="r+").attrs.pop(CHECKSUM_ATTR)
    collect_demos(three, param_list=(0.2, 3.0), resume=True)
    collect_demos(tmp_path / "full.zarr", param_list=(0.2, 3.0))
    full, resumed = load_replay(tmp_path / "full.zarr"), load_replay(three)
    assert resumed.fingerprints == full.fingerprints
    np.testing.assert_array_equal(resumed.data["action"], full.data["action"])
    assert zarr.open_group(str(three)).attrs[CHECKSUM_ATTR] == \
        zarr.open_group(str(tmp_path / "full.zarr")).attrs[CHECKSUM_ATTR]
