"""``impact-export-lerobot`` (``impact_learn/lerobot_export.py``): the LeRobot v3.0 layout, and
the export loaded by lerobot's own ``LeRobotDataset`` in a virtualenv of its own.

The load test needs ``IMPACT_LEROBOT_PYTHON`` (that virtualenv's python;
``tests/learn/lerobot_venv.sh`` makes it; run by hand, not in CI: docs/lerobot.md); it is
skipped with that reason without it."""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from impact_control.errors import InvalidArgumentError
from impact_learn.dataset import EpisodeMeta, ImageSpec, ReplayWriter, load_replay
from impact_learn.lerobot_export import ExportConfig, export_lerobot, main

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")
pytest.importorskip("imageio_ffmpeg")

TESTS = Path(__file__).resolve().parent
HAMMER_DIMS = {"ee_pos": 3, "ee_rot6d": 6, "gripper_width": 1, "joint_pos": 7, "joint_vel": 7,
               "object_pos": 3, "object_rot6d": 6, "goal_pos": 3}
ROBOT = ("ee_pos", "ee_rot6d", "gripper_width", "joint_pos", "joint_vel")
LENGTHS = (7, 5, 6)


def _frames(rng: np.random.Generator, n: int, h: int, w: int, shift: int) -> np.ndarray:
    """Smooth coloured gradients that move from frame to frame (video-codec friendly)."""
    y, x = np.mgrid[0:h, 0:w]
    t = np.arange(n)[:, None, None]
    chans = [(x * 6 + t * 3 + shift) % 256, (y * 8 + t * 2) % 256, ((x + y) * 3 + t + shift) % 256]
    return np.stack(chans, -1).astype(np.uint8)


def _store(path: Path, images: bool, size: tuple[int, int] = (24, 32)) -> Path:
    rng = np.random.default_rng(0)
    dims: dict = dict(HAMMER_DIMS)
    attrs = {"env_id": "IMPACT/Hammer-v1", "param_name": "object_mass"}
    if images:
        dims = {k: dims[k] for k in ROBOT}
        dims |= {f"{c}_rgb": ImageSpec((*size, 3), "uint8") for c in ("overview", "wrist")}
        attrs["observation"] = {"obs_mode": "rgb"}
    writer = ReplayWriter(path, dims, attrs)
    for ep, n in enumerate(LENGTHS):
        obs = {k: rng.normal(size=(n, d)).astype(np.float32)
               for k, d in dims.items() if isinstance(d, int)}
        obs |= {k: _frames(rng, n, *size, 40 * ep) for k, d in dims.items()
                if isinstance(d, ImageSpec)}
        writer.append_episode(obs, rng.uniform(-1, 1, (n, 10)), EpisodeMeta(0.2, ep, True, ep))
    return path


@pytest.fixture(scope="module")
def exports(tmp_path_factory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("lerobot")
    out = {}
    for name in ("state", "rgb"):
        store = _store(root / f"{name}.zarr", images=name == "rgb")
        out[name] = root / f"{name}_lerobot"
        export_lerobot(ExportConfig(str(store), str(out[name]), episodes_per_file=2))
        out[f"{name}_store"] = store
    return out


def test_layout_and_metadata(exports):
    info = json.loads((exports["rgb"] / "meta/info.json").read_text())
    assert info["codebase_version"] == "v3.0" and info["fps"] == 30
    assert info["total_episodes"] == 3 and info["total_frames"] == sum(LENGTHS)
    feats = info["features"]
    assert feats["observation.state"]["shape"] == [24]
    assert feats["observation.state"]["names"][:4] == ["ee_pos.0", "ee_pos.1", "ee_pos.2",
                                                        "ee_rot6d.0"]
    assert feats["observation.images.wrist"]["shape"] == [24, 32, 3]
    state_feats = json.loads((exports["state"] / "meta/info.json").read_text())["features"]
    env_names = state_feats["observation.environment_state"]["names"]
    assert {n.split(".")[0] for n in env_names} == {"object_pos", "object_rot6d", "goal_pos"}
    assert state_feats["observation.environment_state"]["shape"] == [12]
    files = sorted(str(p.relative_to(exports["rgb"])) for p in exports["rgb"].rglob("*.*"))
    assert "data/chunk-000/file-001.parquet" in files  # 2 episodes per file
    assert "videos/observation.images.wrist/chunk-000/file-001.mp4" in files
    episodes = pq.read_table(exports["rgb"] / "meta/episodes/chunk-000/file-000.parquet")
    ep = episodes.to_pydict()
    assert ep["length"] == list(LENGTHS) and ep["data/file_index"] == [0, 0, 1]
    assert ep["videos/observation.images.wrist/from_timestamp"] == [0.0, 7 / 30, 0.0]
    stats = json.loads((exports["rgb"] / "meta/stats.json").read_text())
    assert np.asarray(stats["observation.images.wrist"]["mean"]).shape == (3, 1, 1)
    assert stats["action"]["count"] == [sum(LENGTHS)]


def test_rows_match_the_store(exports):
    store = load_replay(exports["state_store"])
    table = pa.concat_tables(pq.read_table(p) for p in
                             sorted((exports["state"] / "data").rglob("*.parquet")))
    rows = table.to_pydict()
    np.testing.assert_array_equal(np.asarray(rows["action"], np.float32), store.data["action"])
    robot = np.concatenate([store.data[k] for k in ROBOT], 1)
    np.testing.assert_array_equal(np.asarray(rows["observation.state"], np.float32), robot)
    assert rows["frame_index"][:8] == [0, 1, 2, 3, 4, 5, 6, 0]
    assert rows["index"] == list(range(sum(LENGTHS)))


def test_export_is_deterministic(exports, tmp_path):
    again = tmp_path / "again"
    export_lerobot(ExportConfig(str(exports["rgb_store"]), str(again), episodes_per_file=2))

    def digest(root: Path) -> dict[str, str]:
        return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
                for p in root.rglob("*") if p.is_file()}

    assert digest(again) == digest(exports["rgb"])


def test_bad_input_is_one_line(exports, tmp_path, capsys):
    with pytest.raises(InvalidArgumentError, match="exists"):
        export_lerobot(ExportConfig(str(exports["rgb_store"]), str(exports["rgb"])))
    with pytest.raises(InvalidArgumentError, match="valid: even sizes"):
        export_lerobot(ExportConfig(str(_store(tmp_path / "odd.zarr", True, (23, 32))),
                                    str(tmp_path / "odd")))
    assert not (tmp_path / "odd").exists()
    with pytest.raises(SystemExit) as exc:
        main(["--data", str(tmp_path / "missing.zarr"), "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1 and "does not exist" in err


def _lerobot_load(python: str, root: Path, tmp_path: Path) -> dict[str, np.ndarray]:
    out = tmp_path / f"{root.name}.npz"
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "HF_HOME": str(tmp_path / "hf"),
           "HF_DATASETS_CACHE": str(tmp_path / "hf_datasets")}
    proc = subprocess.run([python, str(TESTS / "lerobot_load.py"), str(root), str(out)],
                          env=env, capture_output=True, text=True, timeout=300, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return dict(np.load(out))


@pytest.mark.skipif(not os.environ.get("IMPACT_LEROBOT_PYTHON"),
                    reason="IMPACT_LEROBOT_PYTHON (lerobot's virtualenv) not set: "
                           "tests/learn/lerobot_venv.sh makes it")
@pytest.mark.parametrize("name", ["state", "rgb"])
def test_lerobot_loads_the_export(exports, tmp_path, name):
    got = _lerobot_load(os.environ["IMPACT_LEROBOT_PYTHON"], exports[name], tmp_path)
    store = load_replay(exports[f"{name}_store"])
    assert int(got["num_frames"]) == sum(LENGTHS) and int(got["num_episodes"]) == 3
    assert got["episode_lengths"].tolist() == list(LENGTHS)
    np.testing.assert_array_equal(got["action"], store.data["action"])
    np.testing.assert_array_equal(got["index"], np.arange(sum(LENGTHS)))
    picks = got["item_index"]
    np.testing.assert_array_equal(got["item_action"], store.data["action"][picks])
    robot = np.concatenate([store.data[k] for k in ROBOT], 1)
    np.testing.assert_array_equal(got["item_state"], robot[picks])
    for camera in ("overview", "wrist") if name == "rgb" else ():
        decoded = got[f"item_observation.images.{camera}"]
        raw = store.data[f"{camera}_rgb"][picks].transpose(0, 3, 1, 2) / 255.0
        assert decoded.shape == raw.shape
        assert np.abs(decoded - raw).mean() < 0.03, camera  # H.264 at crf 18, yuv420p


if __name__ == "__main__":  # pragma: no cover
    sys.exit(pytest.main([__file__, "-rs"]))
