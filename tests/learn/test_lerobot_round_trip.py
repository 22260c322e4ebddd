"""``examples/lerobot_round_trip.py``: our demos -> LeRobot dataset -> LeRobot's DiffusionPolicy
-> evaluated back with ``impact_eval.evaluate`` (docs/lerobot.md, "Round trip").

Runs the example, tiny, with ``IMPACT_LEROBOT_PYTHON`` (the virtualenv of
``tests/learn/lerobot_venv.sh``, which holds lerobot and this package); skipped with that reason
without it, as the export's load check (run by hand, not in CI)."""

from __future__ import annotations

import importlib.util
import os
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from impact_learn.dataset import load_replay

pq = pytest.importorskip("pyarrow.parquet")

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "lerobot_round_trip.py"


def _example_module():
    spec = importlib.util.spec_from_file_location("lerobot_round_trip", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.skipif(not os.environ.get("IMPACT_LEROBOT_PYTHON"),
                    reason="IMPACT_LEROBOT_PYTHON (lerobot's virtualenv with this package, "
                           "tests/learn/lerobot_venv.sh) not set: the round trip needs lerobot")
def test_round_trip_trains_in_lerobot_and_evaluates_here(tmp_path) -> None:
    out = tmp_path / "rt"
    env = {**os.environ, "HF_HUB_OFFLINE": "1", "OMP_NUM_THREADS": "1"}
    run = subprocess.run([os.environ["IMPACT_LEROBOT_PYTHON"], str(EXAMPLE), "--out", str(out),
                          "--demos", "3", "--steps", "10", "--batch-size", "8", "--episodes",
                          "2", "--masses", "0.2"], check=True, env=env, cwd=ROOT, timeout=900,
                         capture_output=True, text=True)
    assert "imitation: action position error on demo frames" in run.stdout
    # LeRobot's own checkpoint and processors, saved without pickle
    assert (out / "lerobot_policy" / "model.safetensors").stat().st_size > 0
    for label in ("impedance", "impact", "impact_paper"):
        table = pd.read_csv(out / f"eval_{label}" / "episodes.csv", keep_default_na=False)
        assert len(table) == 2 and set(table["method"]) == {f"lerobot_dp_{label}"}
        # the policy acted for whole episodes: no crash recorded as a failure reason
        assert not table["failure_reason"].str.startswith(("exception", "unstable")).any()
        assert (table["length"] > 0).all()
    # the wrapper rebuilds LeRobot's feature vectors from our observation dict exactly
    columns = _example_module().feature_columns(out / "lerobot_dataset")
    assert set(columns) == {"observation.state", "observation.environment_state"}
    rows = pq.read_table(out / "lerobot_dataset" / "data" / "chunk-000" / "file-000.parquet")
    store = load_replay(out / "demos.zarr")
    for name, cols in columns.items():
        rebuilt = np.stack([store.data[key][:, i] for key, i in cols], axis=1)
        assert np.array_equal(np.stack(rows.column(name).to_numpy(zero_copy_only=False)),
                              rebuilt.astype(np.float32))
