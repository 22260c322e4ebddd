"""``impact-export-lerobot`` never removes what it did not create, and leaves nothing behind
on any error (``impact_learn/lerobot_export.py``): a user's ``OUT.partial`` (folder or file) is
refused, an unwritable ``--out`` is one line, and a failure while writing removes
``OUT.partial`` and every folder the export created for it."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from fixtures.tiny_store import image_store, snapshot

from impact_control.errors import ImpactError, InvalidArgumentError
from impact_learn import lerobot_export, lerobot_write
from impact_learn.lerobot_export import ExportConfig, export_lerobot

pytest.importorskip("pyarrow")
pytest.importorskip("imageio_ffmpeg")


@pytest.fixture(scope="module")
def pristine(tmp_path_factory) -> Path:
    return image_store(tmp_path_factory.mktemp("pristine") / "rgb.zarr", lengths=(20, 12))


@pytest.fixture
def work(pristine, tmp_path) -> Path:
    """A folder holding a copy of the store (the export goes beside it)."""
    shutil.copytree(pristine, tmp_path / "store.zarr")
    return tmp_path


def _cli(argv: list[str], capsys) -> tuple[int, str]:  # noqa: ANN001 - pytest's capsys
    try:
        lerobot_export.main(argv)
        code = 0
    except SystemExit as exc:
        code = int(exc.code or 0)
    return code, capsys.readouterr().err


def test_a_clean_export_leaves_only_out(work):
    export_lerobot(ExportConfig(str(work / "store.zarr"), str(work / "a" / "b" / "lr")))
    assert (work / "a/b/lr/meta/info.json").is_file()
    assert not (work / "a/b/lr.partial").exists()


@pytest.mark.parametrize("kind", ["folder with a file", "empty folder", "file", "symlink"])
def test_a_users_out_partial_is_refused_and_kept(work, kind, capsys):
    partial = work / "lr.partial"
    if kind == "folder with a file":
        partial.mkdir()
        (partial / "notes.txt").write_text("mine")
    elif kind == "empty folder":
        partial.mkdir()
    elif kind == "file":
        partial.write_text("mine")
    else:
        partial.symlink_to(work / "elsewhere")
    before = snapshot(work)
    code, err = _cli(["--data", str(work / "store.zarr"), "--out", str(work / "lr")], capsys)
    assert code == 2 and err.count("\n") == 1 and "lr.partial exists" in err, err
    assert snapshot(work) == before and (partial.exists() or partial.is_symlink())
    assert not (work / "lr").exists()


@pytest.mark.parametrize("out", ["/proc/impact-export-test/lr", "{tmp}/afile/lr",
                                 "{tmp}/afile/deeper/lr"])
def test_an_unwritable_out_is_one_line(work, out, capsys):
    (work / "afile").write_text("x")
    before = snapshot(work)
    code, err = _cli(["--data", str(work / "store.zarr"),
                      "--out", out.replace("{tmp}", str(work))], capsys)
    assert code == 2 and err.count("\n") == 1 and "cannot create" in err, err
    assert "Traceback" not in err and snapshot(work) == before
    assert not Path("/proc/impact-export-test").exists()


def _fail_in_stats(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
    raise OSError(28, "No space left on device")


def _fail_in_video(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
    raise ImpactError("ffmpeg failed on x.mp4: broken pipe")


def _interrupt(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
    raise KeyboardInterrupt


@pytest.mark.parametrize(("target", "fail", "expect"), [
    ("vector_stats", _fail_in_stats, "cannot write"),
    ("_write_videos", _fail_in_video, "ffmpeg failed"),
    ("_episode_table", _interrupt, None),
])
def test_a_failure_while_writing_removes_what_the_export_made(work, monkeypatch, capsys,
                                                              target, fail, expect):
    monkeypatch.setattr(lerobot_write, target, fail)
    before = snapshot(work)
    argv = ["--data", str(work / "store.zarr"), "--out", str(work / "new" / "deeper" / "lr")]
    if expect is None:
        with pytest.raises(KeyboardInterrupt):
            lerobot_export.main(argv)
    else:
        code, err = _cli(argv, capsys)
        assert code == 2 and err.count("\n") == 1 and expect in err, err
    assert snapshot(work) == before and not (work / "new").exists()


def test_an_odd_frame_size_is_refused_before_anything_is_written(tmp_path):
    store = image_store(tmp_path / "odd.zarr", lengths=(5,), size=15)
    with pytest.raises(InvalidArgumentError, match="15x15 frames as yuv420p"):
        export_lerobot(ExportConfig(str(store), str(tmp_path / "x" / "lr")))
    assert not (tmp_path / "x").exists()
