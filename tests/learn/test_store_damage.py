"""A damaged demonstration store is refused by every run that reads or resumes it
(``impact_learn/store_check.py``): ``load_replay``, ``impact-train``, ``impact-export-lerobot``
and ``impact-collect --resume`` (``ReplayWriter(append=True)``) each give one line naming the
damaged array, exit 2 for the CLIs, and leave the store and the output location as they were."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import torch
import zarr
from fixtures.tiny_store import ATTRS, DAMAGES, DIMS, chunk_file, image_store, snapshot

from impact_control.errors import InvalidArgumentError
from impact_learn import lerobot_export
from impact_learn import train as train_module
from impact_learn.dataset import ReplayWriter, load_replay
from impact_learn.store_format import CHECKSUM_ATTR

torch.set_num_threads(1)


@pytest.fixture(scope="module")
def pristine(tmp_path_factory) -> Path:
    return image_store(tmp_path_factory.mktemp("pristine") / "rgb.zarr")


@pytest.fixture
def store(pristine, tmp_path) -> Path:
    return Path(shutil.copytree(pristine, tmp_path / "store.zarr"))


def _exit_code(main, argv: list[str]) -> int:  # noqa: ANN001 - an entry point
    try:
        main(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    return 0


def test_the_pristine_store_loads_with_every_frame(pristine):
    replay = load_replay(pristine)
    assert replay.data["wrist_rgb"].shape == (160, 16, 16, 3)
    assert replay.data["wrist_rgb"][64:128].max() > 0  # not the fill value
    assert len(zarr.open_group(str(pristine)).attrs[CHECKSUM_ATTR]["arrays"]) == 10
    assert CHECKSUM_ATTR not in replay.attrs  # the record stays out of exported metadata


@pytest.mark.parametrize("damage", list(DAMAGES))
def test_load_replay_refuses(store, damage):
    apply, name = DAMAGES[damage]
    apply(store)
    with pytest.raises(InvalidArgumentError) as err:
        load_replay(store)
    assert name in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("damage", list(DAMAGES))
def test_train_cli_refuses_and_writes_nothing(store, damage, tmp_path, capsys):
    apply, name = DAMAGES[damage]
    apply(store)
    before = snapshot(tmp_path)
    argv = ["--data", str(store), "--out", str(tmp_path / "run"), "--steps", "2",
            "--no-progress"]
    assert _exit_code(train_module.main, argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("impact-train: error:") and name in err, err
    assert snapshot(tmp_path) == before and not (tmp_path / "run").exists()


@pytest.mark.parametrize("damage", list(DAMAGES))
def test_export_cli_refuses_and_writes_nothing(store, damage, tmp_path, capsys):
    apply, name = DAMAGES[damage]
    apply(store)
    before = snapshot(tmp_path)
    argv = ["--data", str(store), "--out", str(tmp_path / "exports" / "lr")]
    assert _exit_code(lerobot_export.main, argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("impact-export-lerobot: error:") and name in err
    assert snapshot(tmp_path) == before and not (tmp_path / "exports").exists()


@pytest.mark.parametrize("damage", list(DAMAGES))
def test_resume_refuses_and_leaves_the_store_as_it_was(store, damage):
    apply, name = DAMAGES[damage]
    apply(store)
    before = snapshot(store)
    with pytest.raises(InvalidArgumentError) as err:
        ReplayWriter(store, DIMS, ATTRS, append=True)
    message = str(err.value)
    assert message.startswith(f"cannot resume {store}") and name in message, message
    assert "\n" not in message and snapshot(store) == before


def test_a_store_without_checksums_still_refuses_a_missing_image_chunk(store):
    """Stores written before checksums: chunks must decode and image chunk files exist."""
    zarr.open_group(str(store), mode="r+").attrs.pop(CHECKSUM_ATTR)
    assert load_replay(store).n_episodes == 3
    chunk_file(store, "data/overview_rgb", 1).unlink()
    with pytest.raises(InvalidArgumentError, match="1 of 3 chunk files of data/overview_rgb"):
        load_replay(store)


def test_resume_gives_a_store_without_checksums_its_record(store):
    reference = load_replay(store)
    zarr.open_group(str(store), mode="r+").attrs.pop(CHECKSUM_ATTR)
    ReplayWriter(store, DIMS, ATTRS, append=True)
    assert zarr.open_group(str(store)).attrs[CHECKSUM_ATTR] == \
        zarr.open_group(str(image_store(store.parent / "again.zarr"))).attrs[CHECKSUM_ATTR]
    assert load_replay(store).fingerprints == reference.fingerprints


def test_an_interrupted_record_is_refused_for_reading_and_finished_by_resume(store, tmp_path):
    """A crash between ``episode_ends`` and the record: the last episode has no checksum."""
    short = image_store(tmp_path / "short.zarr", lengths=(70, 50))
    older = zarr.open_group(str(short)).attrs[CHECKSUM_ATTR]
    zarr.open_group(str(store), mode="r+").attrs[CHECKSUM_ATTR] = older
    with pytest.raises(InvalidArgumentError, match="interrupted impact-collect"):
        load_replay(store)
    ReplayWriter(store, DIMS, ATTRS, append=True)
    assert load_replay(store).n_episodes == 3
