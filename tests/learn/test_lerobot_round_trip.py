"""``examples/lerobot_round_trip.py``: our demos -> LeRobot dataset -> LeRobot's DiffusionPolicy
-> evaluated back with ``impact_eval.evaluate`` (docs/lerobot.md, "Round trip").

Runs the example, tiny, with ``IMPACT_LEROBOT_PYTHON`` (the virtualenv of
``tests/learn/lerobot_venv.sh``, which holds lerobot and this package); skipped with that reason
without it, as the export's load check (run by hand, not in CI)."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from impact_learn.dataset import load_replay
from impact_lerobot import PluginSettings, observation_plan

pq = pytest.importorskip("pyarrow.parquet")

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "lerobot_round_trip.py"


@pytest.mark.skipif(not os.environ.get("IMPACT_LEROBOT_PYTHON"),
                    reason="IMPACT_LEROBOT_PYTHON (lerobot's virtualenv with this package, "
                           "tests/learn/lerobot_venv.sh) not set: the round trip needs lerobot")
def test_round_trip_trains_in_lerobot_and_evaluates_here(tmp_path) -> None:
    out = tmp_path / "rt"
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "OMP_NUM_THREADS": "1"}
    run = subprocess.run([os.environ["IMPACT_LEROBOT_PYTHON"], str(EXAMPLE), "--out", str(out),
                          "--demos", "3", "--steps", "10", "--batch-size", "8", "--episodes",
                          "2", "--masses", "0.2", "--save-every", "10"], check=True, env=env,
                         cwd=ROOT, timeout=900, capture_output=True, text=True)
    assert "imitation: action position error on demo frames" in run.stdout
    for label in ("impedance", "impact", "impact_paper"):
        table = pd.read_csv(out / f"eval_{label}" / "episodes.csv", keep_default_na=False)
        assert len(table) == 2 and set(table["method"]) == {f"round_trip_{label}"}
        # the policy acted for whole episodes: no crash recorded as a failure reason
        assert not table["failure_reason"].str.startswith(("exception", "unstable")).any()
        assert (table["length"] > 0).all()
    # LeRobot's own checkpoint folder, saved without pickle
    model = out / "lerobot_train" / "checkpoints" / "last" / "pretrained_model"
    assert (model / "model.safetensors").stat().st_size > 0
    # the adapter (impact_lerobot.policy) rebuilds LeRobot's feature vectors from our
    # observation dict exactly: the batch it feeds equals the export's parquet rows
    rows = pq.read_table(out / "lerobot_dataset" / "data" / "chunk-000" / "file-000.parquet")
    store = load_replay(out / "demos.zarr")
    batch = observation_plan(PluginSettings(task="Hammer-v1")).policy_batch(store.data)
    assert set(batch) == {"observation.state", "observation.environment_state"}
    for name, values in batch.items():
        assert np.array_equal(np.stack(rows.column(name).to_numpy(zero_copy_only=False)), values)
