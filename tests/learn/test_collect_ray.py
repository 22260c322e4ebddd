"""``impact-collect --executor ray`` (``impact_learn/collect_ray.py``): the same store as a local
run, a worker killed mid-batch, and resume across executors (2-CPU Ray in this process)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fixtures.fake_reach import FAKE_ID, FakeExpert, make_reach

from impact_learn import collect as collect_module
from impact_learn.collect import collect
from impact_learn.collect_config import CollectConfig
from impact_learn.dataset import load_replay

pytest.importorskip("ray")


def _collect(out: Path, executor: str, **changes) -> int:
    fields = {"env_id": FAKE_ID, "out": str(out), "episodes": 10, "n_envs": 2,
              "progress": False, "param_range": (0.1, 8.0), "post_success_steps": 2,
              "executor": executor}
    return collect(CollectConfig(**{**fields, **changes}), env_factory=make_reach,
                   expert_factory=FakeExpert)


def assert_same_store(a: Path, b: Path) -> None:
    """Equal data, metadata, episode ends and attributes."""
    x, y = load_replay(a), load_replay(b)
    assert set(x.data) == set(y.data) and set(x.meta) == set(y.meta)
    for key in x.data:
        np.testing.assert_array_equal(x.data[key], y.data[key])
    for key in x.meta:
        np.testing.assert_array_equal(x.meta[key], y.meta[key])
    np.testing.assert_array_equal(x.episode_ends, y.episode_ends)
    assert x.attrs == y.attrs


@pytest.fixture(scope="module")
def local_store(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("collect") / "local.zarr"
    assert _collect(out, "local") == 10
    assert load_replay(out).attrs["n_attempts"] > 10  # heavy masses fail: several batches
    return out


def test_ray_collection_stores_what_a_local_run_stores(ray_local, local_store, tmp_path,
                                                      monkeypatch):
    import ray

    def no_cancel(*args: object, **kwargs: object) -> None:
        raise AssertionError("ray.cancel races a finishing task's reply (impact_envs.parallel)")

    monkeypatch.setattr(ray, "cancel", no_cancel)  # the batches left over are dropped
    assert _collect(tmp_path / "ray.zarr", "ray") == 10
    assert_same_store(tmp_path / "ray.zarr", local_store)


@pytest.mark.slow  # ~100 s (Ray restarts a killed worker); --runslow
def test_a_worker_killed_mid_batch_changes_nothing(ray_local, local_store, tmp_path):
    (ray_local / "fired").unlink(missing_ok=True)
    (ray_local / "arm").touch()
    try:
        assert _collect(tmp_path / "ray.zarr", "ray") == 10
    finally:
        (ray_local / "arm").unlink()
    assert (ray_local / "fired").exists(), "no worker was killed"
    assert_same_store(tmp_path / "ray.zarr", local_store)


@pytest.mark.parametrize("first, then", [
    ("local", "ray"),
    pytest.param("ray", "local", marks=pytest.mark.slow)])  # ~130 s; --runslow
def test_resume_across_executors(ray_local, local_store, tmp_path, first, then):
    out = tmp_path / "cut.zarr"
    assert _collect(out, first, episodes=4) == 4
    assert _collect(out, then, resume=True) == 10
    assert_same_store(out, local_store)


def test_collect_cli_takes_the_executor(tmp_path, capsys):
    argv = ["--env", FAKE_ID, "--out", str(tmp_path / "x.zarr"), "--executor", "spark"]
    with pytest.raises(SystemExit) as exc:
        collect_module.main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "valid choices: local, ray" in err
    assert not (tmp_path / "x.zarr").exists()
