"""``impact-train --resume`` refuses data and flags other than the run's
(``impact_learn/train.py``, ``train_resume.py``): one line naming what differs and both
values, exit 2, and the run folder byte for byte as it was."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
import torch
import zarr
from fixtures.tiny_store import chunk_file, image_store, snapshot

from impact_envs.policies.diffusion.config import DiffusionConfig, ImageEncoderConfig
from impact_learn import train as train_module
from impact_learn.store_format import CHECKSUM_ATTR

torch.set_num_threads(1)
VISION = ImageEncoderConfig(image_keys=("overview_rgb", "wrist_rgb"), channels=(8, 8),
                            keypoints=4, feature_dim=8)
CFG = DiffusionConfig(obs_keys=("ee_pos", "gripper_width"), down_dims=(16, 32),
                      diffusion_step_embed_dim=16, num_inference_steps=4, batch_size=8,
                      vision=VISION)


@pytest.fixture(scope="module")
def started(tmp_path_factory) -> dict[str, Path]:
    """A store, a config file and a visuomotor run of 2 steps on them (copied per test)."""
    root = tmp_path_factory.mktemp("run")
    store = image_store(root / "rgb.zarr", lengths=(20, 12, 10))
    config = root / "cfg.json"
    CFG.to_json(config)
    code = _run(["--data", str(store), "--out", str(root / "run"), "--steps", "2",
                 "--config", str(config), "--val-fraction", "0.34"])
    assert code == 0
    return {"root": root, "store": store, "config": config, "run": root / "run"}


@pytest.fixture
def run(started, tmp_path) -> Path:
    return Path(shutil.copytree(started["run"], tmp_path / "run"))


def _run(argv: list[str]) -> int:
    try:
        train_module.main([*argv, "--no-progress", "--checkpoint-every", "2", "--val-every",
                           "2"])
    except SystemExit as exc:
        return int(exc.code or 0)
    return 0


def _resume(run: Path, store: Path, *extra: str) -> list[str]:
    return ["--data", str(store), "--out", str(run), "--steps", "4", "--resume", *extra]


def _refused(argv: list[str], run: Path, capsys, *parts: str) -> None:  # noqa: ANN001
    before = snapshot(run)
    assert _run(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("impact-train: error:"), err
    assert all(part in err for part in parts), err
    assert snapshot(run) == before


@pytest.mark.parametrize(("variant", "names"), [
    ("cameras swapped", ("data/overview_rgb", "data/wrist_rgb")),
    ("wrist images changed", ("data/wrist_rgb",)),
])
def test_other_images_are_refused(run, tmp_path, capsys, variant, names):
    other = image_store(tmp_path / "other.zarr", lengths=(20, 12, 10),
                        swap=variant == "cameras swapped",
                        wrist_shift=7 if variant == "wrist images changed" else 100)
    _refused(_resume(run, other), run, capsys, *names, "not the data the run")


@pytest.mark.parametrize(("array", "chunk"), [("data/wrist_rgb", 0), ("data/ee_pos", 0)])
def test_a_damaged_store_is_refused_on_resume(started, run, tmp_path, capsys, array, chunk):
    store = Path(shutil.copytree(started["store"], tmp_path / "damaged.zarr"))
    chunk_file(store, array, chunk).unlink()
    _refused(_resume(run, store), run, capsys, array, "the store is damaged")


def test_swapped_folders_of_a_store_without_checksums_are_refused(started, run, tmp_path,
                                                                   capsys):
    store = Path(shutil.copytree(started["store"], tmp_path / "old.zarr"))
    zarr.open_group(str(store), mode="r+").attrs.pop(CHECKSUM_ATTR)
    (store / "data/overview_rgb").rename(store / "data/tmp")
    (store / "data/wrist_rgb").rename(store / "data/overview_rgb")
    (store / "data/tmp").rename(store / "data/wrist_rgb")
    _refused(_resume(run, store), run, capsys, "data/overview_rgb", "data/wrist_rgb")


@pytest.mark.parametrize(("flags", "parts"), [
    (("--batch-size", "4"), ("--batch-size sets batch_size 4", "has batch_size 8")),
    (("--seed", "3"), ("--seed sets seed 3", "has seed 0")),
    (("--val-fraction", "0.5"), ("--val-fraction 0.5", "the run's 0.34")),
    (("--config", "{lr}"), ("--config", "sets lr 0.003", "has lr 0.0001")),
    (("--config", "{horizon}"), ("--config", "sets horizon 32", "has horizon 16")),
])
def test_flags_that_define_the_run_cannot_change(started, run, tmp_path, capsys, flags, parts):
    files = {"{lr}": {**CFG.to_dict(), "lr": 0.003}, "{horizon}": {"horizon": 32}}
    argv = list(flags)
    if argv[-1] in files:
        path = tmp_path / "other.json"
        path.write_text(json.dumps(files[argv[-1]]))
        argv[-1] = str(path)
    _refused(_resume(run, started["store"], *argv), run, capsys, *parts)


def test_the_same_flags_and_a_moved_store_resume(started, run, tmp_path):
    moved = Path(shutil.copytree(started["store"], tmp_path / "moved.zarr"))
    partial = tmp_path / "partial.json"
    partial.write_text(json.dumps({"batch_size": 8, "lr": CFG.lr}))  # the fields it names agree
    argv = _resume(run, moved, "--config", str(partial), "--batch-size", "8", "--seed", "0",
                   "--val-fraction", "0.34", "--threads", "1")
    assert _run(argv) == 0
    state = json.loads((run / "train_state/state.json").read_text())
    assert state["step"] == 4 and state["info"]["val_fraction"] == 0.34
    assert set(state["info"]["data_fingerprints"]) == {
        "data/ee_pos", "data/gripper_width", "data/overview_rgb", "data/wrist_rgb",
        "data/action", "meta/episode_ends"}
