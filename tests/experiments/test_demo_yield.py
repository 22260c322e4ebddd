"""``impact_experiments.demo_yield``: attempts kept and failed per mass band, the
attempts' masses recomputed from the store's seed and range as impact-collect drew them."""

from __future__ import annotations

import numpy as np
import pytest
import zarr

from impact_experiments.demo_yield import main, yield_by_band
from impact_learn.collect_config import CollectConfig
from impact_learn.collect_run import attempt_param


def _store(path, kept: list[int], seed: int = 3) -> str:
    root = zarr.open_group(str(path), mode="w")
    root.create_array("data/action", data=np.zeros((len(kept), 10)))
    root.create_array("meta/episode_ends", data=np.arange(1, len(kept) + 1))
    root.create_array("meta/episode_attempt", data=np.array(kept))
    root.attrs.update({"env_id": "IMPACT/HammerBasket-v1", "seed": seed,
                       "param_spec": {"mode": "uniform", "values": [0.1, 10.0]},
                       "expert": {"name": "authors", "compensation": "privileged"}})
    return str(path)


def test_failed_attempts_are_counted_in_the_band_of_their_drawn_mass(tmp_path) -> None:
    kept = [0, 2, 3, 6]  # attempts 1, 4, 5 failed; 7 and later are not counted
    lines = yield_by_band(_store(tmp_path / "s.zarr", kept), bands=2)
    assert lines[0].endswith("4 kept of 7 attempts (3 failed), expert {'name': 'authors', "
                             "'compensation': 'privileged'}")
    cfg = CollectConfig(env_id="IMPACT/HammerBasket-v1", out="x", seed=3,
                        param_range=(0.1, 10.0))
    light = [a for a in range(7) if attempt_param(cfg, a) < 5.05]
    failed_light = [a for a in light if a not in kept]
    assert f"{len(light) - len(failed_light)} kept of {len(light)} attempts " \
           f"({len(failed_light)} failed)" in lines[1]


def test_a_store_without_a_range_is_one_line(tmp_path, capsys) -> None:
    path = _store(tmp_path / "s.zarr", [0])
    zarr.open_group(path, mode="a").attrs["param_spec"] = {"mode": "fixed", "values": [1.0]}
    with pytest.raises(SystemExit) as exc:
        main(["--data", path])
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert exc.value.code == 2 and "valid: a store written by impact-collect --mass-range" in err
