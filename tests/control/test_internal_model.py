"""Internal model: fast path vs torch, gate behaviour, online learning, persistence."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch
from fixtures.torch_mlp import as_torch, fill_randn

from impact_control.config import InternalModelConfig
from impact_control.errors import CheckpointError, InvalidArgumentError
from impact_control.internal_model import (
    FEATURE_DIM,
    FEATURE_OFFSET,
    FEATURE_SCALE,
    InternalModel,
)
from impact_control.internal_model.gate import SurpriseGate
from impact_control.internal_model.net import OUTPUT_SCALE, build_network, sgd_step
from impact_control.presets import preset_config

torch.set_num_threads(1)

Q = np.array([0.1, -0.4, 0.2, -2.0, 0.1, 1.8, 0.7])
POS = np.array([0.5, 0.1, 0.25])
PAYLOAD = np.array([0.0, 0.0, 24.5, 0.0, 0.0, 0.0])  # 2.5 kg, robot-on-environment sign


def _push(model: InternalModel, w_ext: np.ndarray, dq: np.ndarray | None = None) -> None:
    model.push(Q, np.zeros(7) if dq is None else dq, 0.03, POS, w_ext)


def _run(model: InternalModel, w_slow: np.ndarray, ticks: int, slow_rate: float = 0.0, mask=None):
    for _ in range(ticks):
        _push(model, w_slow)
        model.step(w_slow, slow_rate, mask)
    return model.predict().copy()


def test_initial_prediction_is_zero_and_history_layout() -> None:
    model = InternalModel()
    np.testing.assert_array_equal(model.predict(), 0.0)
    for k in range(40):
        model.push(Q + k, np.full(7, k), 0.01 * k, POS, np.full(6, float(k)))
    x = model.history_input().reshape(32, FEATURE_DIM)
    z = np.concatenate([Q + 39, np.full(7, 39.0), [0.39], POS, np.full(6, 39.0)])
    np.testing.assert_allclose(x[-1], (z - FEATURE_OFFSET) / FEATURE_SCALE, rtol=1e-6)
    np.testing.assert_allclose(x[0, 7], 8.0)  # oldest of the last 32 ticks is k = 8 (dq scale 1)


def test_first_push_fills_history() -> None:
    model = InternalModel()
    _push(model, PAYLOAD)
    x = model.history_input().reshape(32, FEATURE_DIM)
    np.testing.assert_array_equal(x, np.broadcast_to(x[-1], x.shape))


def test_numba_fast_path_matches_torch() -> None:
    model = InternalModel(InternalModelConfig(seed=3))
    fill_randn(model.net, 0)
    reference = as_torch(model.net)
    rng = np.random.default_rng(1)
    for _ in range(40):
        model.push(Q + rng.normal(size=7), rng.normal(size=7), 0.04, POS, rng.normal(size=6) * 10)
        fast = model.predict().copy()
        with torch.no_grad():
            x = torch.from_numpy(model.history_input().copy())[None]
            ref = reference(x)[0].numpy().astype(np.float64) * OUTPUT_SCALE
        np.testing.assert_allclose(model.predict_reference(), ref, rtol=1e-5, atol=1e-5)
        assert np.abs(ref).max() > 0.1  # a non-trivial network
        np.testing.assert_allclose(fast, ref, rtol=1e-5, atol=1e-5)


def test_learns_constant_payload_when_gate_opens() -> None:
    model = InternalModel()
    _push(model, PAYLOAD)
    model.step(PAYLOAD, 0.0)
    assert model.gate.is_open and model.surprise_n == pytest.approx(24.5)
    pred = _run(model, PAYLOAD, 1500)
    np.testing.assert_allclose(pred, PAYLOAD, atol=0.5)
    assert not model.gate.is_open  # released below 0.5 N
    assert 0 < model.n_updates < 300  # quick: fewer than 300 SGD steps (1.5 s at 1 update / 5 ms)


def test_gate_stays_closed_below_threshold() -> None:
    model = InternalModel(preset_config("paper").internal_model)
    small = np.array([3.0, 0.0, 3.5, 0.0, 0.0, 0.0])  # |f| = 4.6 N < 5 N
    pred = _run(model, small, 500)
    assert model.n_updates == 0 and not model.gate.is_open
    np.testing.assert_array_equal(pred, 0.0)
    model = InternalModel()  # default preset: opens at 2.5 N
    small = np.array([1.5, 0.0, 1.9, 0.0, 0.0, 0.0])  # |f| = 2.42 N
    pred = _run(model, small, 500)
    assert model.n_updates == 0 and not model.gate.is_open
    np.testing.assert_array_equal(pred, 0.0)


def test_gate_waits_for_quasi_steady_slow_wrench() -> None:
    model = InternalModel(preset_config("paper").internal_model)
    _run(model, PAYLOAD, 300, slow_rate=0.5)  # w_slow still moving: no learning
    assert model.n_updates == 0 and not model.gate.is_open
    _run(model, PAYLOAD, 10, slow_rate=0.1)
    assert model.gate.is_open and model.n_updates == 2


def test_learn_mask_freezes_axis() -> None:
    model = InternalModel()
    target = np.array([8.0, 0.0, 24.5, 0.0, 0.0, 0.0])
    mask = np.array([True, True, False, True, True, True])
    pred = _run(model, target, 1500, mask=mask)
    assert pred[0] == pytest.approx(8.0, abs=0.5)
    assert abs(pred[2]) < 0.5  # z frozen at its initial prediction 0
    assert not model.gate.is_open  # surprise ignores the frozen axis


def test_schmitt_gate() -> None:
    gate = SurpriseGate(5.0, 0.5, 0.2)
    assert gate.update(4.9, 0.0) is False
    assert gate.update(5.0, 0.3) is False and not gate.is_open  # not quasi-steady
    assert gate.update(5.0, 0.1) is True
    assert gate.update(2.0, 0.1) is True  # hysteresis: still learning
    assert gate.update(2.0, 0.5) is False and gate.is_open  # paused, still latched
    assert gate.update(0.4, 0.1) is False and not gate.is_open
    literal = SurpriseGate(5.0, 5.0, 0.2)
    assert literal.update(6.0, 0.0) is True
    assert literal.update(4.0, 0.0) is False  # single threshold


def test_reset_history_keeps_weights_reinitialize_clears() -> None:
    model = InternalModel()
    pred = _run(model, PAYLOAD, 600)
    model.reset_history()
    _push(model, PAYLOAD)
    np.testing.assert_allclose(model.predict(), pred, atol=1e-6)
    model.reinitialize()
    _push(model, PAYLOAD)
    np.testing.assert_array_equal(model.predict(), 0.0)
    assert model.replay.count == 0 and model.n_updates == 0


def test_save_load_round_trip(tmp_path: Path) -> None:
    model = InternalModel(InternalModelConfig(hidden_sizes=(32, 16)))
    _run(model, PAYLOAD, 400)
    path = model.save(tmp_path / "im.safetensors")
    assert path.with_suffix(".json").is_file()
    for loaded in (InternalModel.from_file(path), InternalModel(model.config)):
        loaded.load(path)
        model.reset_history()
        rng = np.random.default_rng(2)
        for _ in range(5):
            args = (Q + rng.normal(size=7), rng.normal(size=7), 0.02, POS, rng.normal(size=6))
            model.push(*args)
            loaded.push(*args)
            np.testing.assert_array_equal(loaded.predict(), model.predict())
            assert abs(model.predict()[2]) > 5.0  # the trained weights, not the initial zeros


FMA_CPU = torch.backends.cpu.get_cpu_capability() in ("AVX2", "AVX512")


@pytest.mark.skipif(not FMA_CPU, reason="torch's uniform_ fuses its multiply-add only with FMA")
@pytest.mark.parametrize(("seed", "hidden", "history"), [(0, (64, 64), 32), (7, (32, 16), 4),
                                                        (12345, (5,), 1)])
def test_initial_weights_are_torch_linear_init_bit_for_bit(seed: int, hidden: tuple[int, ...],
                                                           history: int) -> None:
    """``build_network`` draws what ``torch.manual_seed(seed)`` + ``torch.nn.Linear`` would,
    without torch; the last layer is zeroed after its draws."""
    net = build_network(InternalModelConfig(seed=seed, hidden_sizes=hidden,
                                            history_length=history))
    state = torch.random.get_rng_state()
    torch.manual_seed(seed)
    sizes = (history * FEATURE_DIM, *hidden, 6)
    linears = [torch.nn.Linear(a, b) for a, b in zip(sizes[:-1], sizes[1:], strict=True)]
    torch.random.set_rng_state(state)
    for k, linear in enumerate(linears):
        w, b = linear.weight.detach().numpy(), linear.bias.detach().numpy()
        if k == len(linears) - 1:
            w, b = np.zeros_like(w), np.zeros_like(b)
        assert net.weights[k].dtype == np.float32 and np.array_equal(net.weights[k], w)
        assert np.array_equal(net.biases[k], b)


def test_saved_weights_are_torchs_safetensors_layout(tmp_path: Path) -> None:
    """A file saved without torch loads in torch under the Sequential's names, and one saved
    from torch tensors loads into the model."""
    from safetensors.torch import load_file, save_file

    model = InternalModel(InternalModelConfig(hidden_sizes=(8,), history_length=2))
    fill_randn(model.net, 3)
    path = model.save(tmp_path / "m.safetensors")
    reference = as_torch(model.net)
    loaded = load_file(str(path))
    assert set(loaded) == set(reference.state_dict())
    for k, v in reference.state_dict().items():
        assert torch.equal(loaded[k], v)
    save_file({k: 2 * v for k, v in reference.state_dict().items()}, str(path))
    model.load(path)
    np.testing.assert_array_equal(model.net.weights[0], 2 * reference[0].weight.detach().numpy())


def test_load_rejects_mismatched_or_missing(tmp_path: Path) -> None:
    path = InternalModel().save(tmp_path / "a.safetensors")
    with pytest.raises(CheckpointError):
        InternalModel(InternalModelConfig(hidden_sizes=(32, 32))).load(path)
    with pytest.raises(CheckpointError):
        InternalModel().load(tmp_path / "missing.safetensors")


@pytest.mark.parametrize(
    "kwargs",
    [
        {"history_length": 0},
        {"hidden_sizes": ()},
        {"surprise_release_n": 6.0},
        {"learning_rate": -1.0},
        {"update_every": 0},
    ],
)
def test_config_validation(kwargs: dict) -> None:
    with pytest.raises(InvalidArgumentError):
        InternalModelConfig(**kwargs)


def test_sgd_step_matches_autograd() -> None:
    """The hand-written gradients give the autograd + torch.optim.SGD update."""
    model = InternalModel(InternalModelConfig(hidden_sizes=(32, 16)))
    gen = fill_randn(model.net, 4)
    reference = as_torch(model.net)
    x = torch.randn(16, model.input_dim, generator=gen)
    y = torch.randn(16, 6, generator=gen)
    mask = (torch.rand(16, 6, generator=gen) > 0.3).float()
    optimizer = torch.optim.SGD(reference.parameters(), lr=0.01)
    expected_loss = ((reference(x) - y) * mask).square().mean()
    optimizer.zero_grad()
    expected_loss.backward()
    optimizer.step()
    _, weights, biases, _, _ = model.kernel_args()  # the network's own arrays
    loss = sgd_step(weights, biases, x.numpy(), y.numpy(), mask.numpy(), 0.01)
    assert loss == pytest.approx(float(expected_loss.detach()), rel=1e-6)
    for p, p_ref in zip(model.net.parameters(), reference.parameters(), strict=True):
        np.testing.assert_allclose(p, p_ref.detach().numpy(), atol=1e-7)


def test_wrench_feature_off_hides_the_estimated_wrench_from_the_network() -> None:
    model = InternalModel(InternalModelConfig(wrench_feature=False))
    q, dq, p = np.full(7, 0.2), np.zeros(7), np.array([0.5, 0.0, 0.3])
    model.push(q, dq, 0.03, p, np.array([0.0, 0.0, 40.0, 0.0, 0.0, 1.0]))
    with_load = model.history_input().copy()
    model.reset_history()
    model.push(q, dq, 0.03, p, np.zeros(6))
    np.testing.assert_array_equal(model.history_input(), with_load)  # same input either way
    assert InternalModel().config.wrench_feature  # both presets see it


def test_a_diverging_sgd_step_reinitializes_instead_of_feeding_non_finite_weights() -> None:
    """Inputs far outside any payload (a 1e5 N wrench, saturated features) make plain SGD at
    lr 0.1 diverge; the step that leaves a non-finite loss or weight restores the seeded
    model, so the prediction fed forward stays finite."""
    model = InternalModel()
    fresh = [w.copy() for w in model.kernel_args()[1]]
    huge = np.array([1e5, -1e5, 1e5, 1e4, -1e4, 1e4])
    for _ in range(3000):
        model.push(Q * 10.0, np.full(7, 100.0), 1.0, POS * 100.0, huge)
        model.train_step(model.history_input(), (huge / 10.0).astype(np.float32),
                         np.ones(6, np.float32))
        assert np.all(np.isfinite(model.predict()))
        if model.n_divergences:
            break
    assert model.n_divergences == 1
    assert model.replay.count == 0 and model.n_updates == 0
    for w, w0 in zip(model.kernel_args()[1], fresh, strict=True):
        np.testing.assert_array_equal(w, w0)


@pytest.mark.parametrize("mask", [np.ones(3), np.full(6, np.nan), np.full(6, 2.0), 1.0])
def test_learn_mask_must_be_six_weights_in_unit_interval(mask) -> None:
    with pytest.raises(InvalidArgumentError, match="invalid learn_mask"):
        InternalModel().mask_array(mask)
