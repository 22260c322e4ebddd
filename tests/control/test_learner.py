"""The in-kernel learner (``internal_model/learner.py``): replay ring, sampler, spread SGD."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from fixtures.torch_mlp import as_torch, fill_randn

from impact_control.config import ControllerConfig, InternalModelConfig
from impact_control.errors import InvalidArgumentError
from impact_control.ik import HOME_Q
from impact_control.internal_model import InternalModel
from impact_control.internal_model.learner import (
    DIVERGED,
    continue_step,
    replay_store,
    splitmix64_below,
    start_step,
    unpack_counters,
)


def _model(per_tick: int, seed: int = 4, hidden: tuple[int, ...] = (32, 16)) -> InternalModel:
    cfg = InternalModelConfig(hidden_sizes=hidden, learner="numba", samples_per_tick=per_tick,
                              learning_rate=0.01)
    model = InternalModel(cfg)
    fill_randn(model.net, seed)
    rng = np.random.default_rng(seed)
    for _ in range(40):
        replay_store(rng.normal(size=model.input_dim).astype(np.float32),
                     rng.normal(size=6).astype(np.float32),
                     (rng.random(6) > 0.3).astype(np.float32), model.learner)
    return model


def _step(model: InternalModel, x: np.ndarray, y: np.ndarray, m: np.ndarray) -> int:
    """Start one step and run ticks until it is applied; returns the number of ticks."""
    _, weights, biases, _, lrn = model.kernel_args()
    start_step(x, y, m, lrn)
    ticks = 0
    while unpack_counters(lrn.scal)[0].pending[0]:
        assert continue_step(weights, biases, lrn) == 0
        ticks += 1
    return ticks


def test_one_in_kernel_step_is_the_autograd_sgd_step_on_its_batch() -> None:
    model = _model(per_tick=16)
    reference = as_torch(model.net)
    rng = np.random.default_rng(1)
    x = rng.normal(size=model.input_dim).astype(np.float32)
    y, m = rng.normal(size=6).astype(np.float32), np.ones(6, np.float32)
    assert _step(model, x, y, m) == 1
    lrn = model.learner
    assert np.array_equal(lrn.batch_x[0], x)  # row 0: the current sample
    bx, by, bm = (torch.from_numpy(a.copy()) for a in (lrn.batch_x, lrn.batch_y, lrn.batch_m))
    loss = ((reference(bx) - by) * bm).square().mean()
    loss.backward()
    with torch.no_grad():
        for p in reference.parameters():
            p -= 0.01 * p.grad
    for p, p_ref in zip(model.net.parameters(), reference.parameters(), strict=True):
        np.testing.assert_allclose(p, p_ref.detach().numpy(), atol=2e-7)
    assert model.n_updates == 1


def test_a_step_spread_over_ticks_equals_the_whole_step_bit_for_bit() -> None:
    whole, spread = _model(per_tick=16), _model(per_tick=4)
    rng = np.random.default_rng(2)
    for _ in range(5):
        x = rng.normal(size=whole.input_dim).astype(np.float32)
        y, m = rng.normal(size=6).astype(np.float32), np.ones(6, np.float32)
        assert _step(whole, x, y, m) == 1
        assert _step(spread, x, y, m) == 4
    for a, b in zip(whole.net.parameters(), spread.net.parameters(), strict=True):
        assert np.array_equal(a, b)


def test_sampler_is_seeded_uniform_and_restarts_with_the_model() -> None:
    rng = np.zeros(1, np.uint64)
    draws = np.array([splitmix64_below(rng, 7) for _ in range(70000)])
    counts = np.bincount(draws, minlength=7)
    assert draws.min() == 0 and draws.max() == 6
    assert np.all(np.abs(counts - 10000) < 400)  # > 4 sigma of a binomial(70000, 1/7)
    model = _model(per_tick=4)
    model.reset_history()
    first = int(model.learner.rng[0])
    start_step(np.zeros(model.input_dim, np.float32), np.zeros(6, np.float32),
               np.ones(6, np.float32), model.learner)
    assert int(model.learner.rng[0]) != first
    model.reset_history()  # drops the pending step and reseeds
    assert int(model.learner.rng[0]) == first
    assert unpack_counters(model.learner.scal)[0].pending[0] == 0


def test_a_diverging_in_kernel_step_is_reported() -> None:
    model = _model(per_tick=16)
    _, weights, biases, _, lrn = model.kernel_args()
    start_step(np.ones(model.input_dim, np.float32), np.full(6, np.inf, np.float32),
               np.ones(6, np.float32), lrn)  # a non-finite loss
    assert continue_step(weights, biases, lrn) == DIVERGED


def test_numba_learner_in_the_controller_learns_a_payload() -> None:
    """A 3 kg payload held under the in-kernel learner: SGD steps run inside the tick and the
    prediction learns the load (robot-on-environment sign: +z)."""
    from impact_experiments.physics import Rig

    rig = Rig.build("payload_scene.xml", "impact", "residual", seed=0)
    cfg = ControllerConfig(internal_model=InternalModelConfig(learner="numba"))
    rig = Rig(rig.sim, rig.arm, type(rig.controller)(rig.arm, cfg, mode="impact"), rig.rng)
    model = rig.sim.model
    body = model.body("payload").id
    inertia = model.body_inertia[body] / model.body_mass[body]
    model.body_mass[body] = 1e-6
    pos, quat = rig.start(HOME_Q)
    rig.run(pos, quat, 0.5)
    model.body_mass[body], model.body_inertia[body] = 3.0, inertia * 3.0
    rig.run(pos, quat, 1.5)
    im = rig.controller.internal_model
    assert im.n_updates > 50 and im.replay.count > 50 and im.n_divergences == 0
    assert im.wrench_pred_world[2] == pytest.approx(3.0 * 9.81, rel=0.05)
    assert pos[2] - rig.sim.tcp_pose()[0][2] < 5e-3  # impedance alone: m g / K = 74 mm


def test_spread_must_finish_before_the_next_step() -> None:
    with pytest.raises(InvalidArgumentError, match="samples_per_tick"):
        InternalModelConfig(learner="numba", samples_per_tick=2, update_every=5, batch_size=16)
    with pytest.raises(InvalidArgumentError, match="numpy"):
        InternalModelConfig(learner="torch")


def test_tick_latency_benchmark_runs_and_reports_both_learners(tmp_path) -> None:
    import json

    from impact_experiments import tick_latency

    assert tick_latency.main(["--seconds", "0.3", "--switch-s", "0.1", "--out",
                              str(tmp_path)]) == 0
    report = json.loads((tmp_path / "latency.json").read_text())
    for learner in ("numpy", "numba"):
        assert report[learner]["all"]["ticks"] == 300
        assert report[learner]["sgd_steps"] > 0  # the payload switches made it learn
