"""The warm-robot rows of impact-eval (``MethodSpec.warm``): one unscored warm-up per cell."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from impact_eval.method_parts import policy_part
from impact_eval.methods import MethodSpec, register_method, resolve_method
from impact_eval.spec import RunOptions, SweepSpec
from impact_eval.sweep import SweepConfig, Worker

WARM = MethodSpec("scripted_impact_warm_test", "impact", policy_part("scripted").build,
                  "scripted expert, IMPACT, warm (test)", warm=True)


def _config() -> SweepConfig:
    spec = SweepSpec(env_id="IMPACT/Hammer-v1", methods=(WARM.name,), values=(0.2, 2.5),
                     episodes=2, seed=5)
    return SweepConfig(spec, RunOptions(out=Path("unused"), envs_per_worker=2),
                       canonical_env_id="IMPACT/Hammer-v1", param_name="object_mass",
                       policy_dt=1 / 30)


def test_builtin_warm_method_is_registered() -> None:
    spec = resolve_method("impact_warm")
    assert spec.warm and spec.controller == "impact" and spec.preset == "default"
    assert resolve_method("impact_paper").preset == "paper"


@pytest.mark.slow
def test_warm_snapshot_is_learned_cached_and_deterministic() -> None:
    register_method(WARM)
    first, second = Worker(_config()), Worker(_config())
    try:
        snap = first._warm_snapshot(WARM, 2.5)
        assert first._warm_snapshot(WARM, 2.5) is snap  # one warm-up per cell and worker
        assert snap.replay.count > 0  # the warm-up learned something (the 2.5 kg hammer)
        other = second._warm_snapshot(WARM, 2.5)  # another worker computes the same model
        for k, v in snap.weights.items():
            np.testing.assert_array_equal(v, other.weights[k])
        np.testing.assert_array_equal(snap.replay.targets, other.replay.targets)
        env = first._envs(WARM, 1)[0]
        env.unwrapped.warm_start(snap)
        env.reset(seed=0, options={"object_mass": 2.5})
        model = env.unwrapped.controller.internal_model
        for k, v in model.net.state_dict().items():
            np.testing.assert_array_equal(v, snap.weights[k])
    finally:
        first.close()
        second.close()
