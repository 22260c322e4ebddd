"""DiffusionPolicy: protocol behaviour, receding horizon, checkpoint round-trip and errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
import torch

from impact_control.errors import CheckpointError, InvalidArgumentError
from impact_control.policy import Policy
from impact_envs.policies.diffusion.config import DiffusionConfig
from impact_envs.policies.diffusion.policy import DiffusionPolicy
from impact_experiments.dp_inference_cost import main as bench_main
from impact_experiments.dp_inference_cost import measure_inference, random_policy

torch.set_num_threads(1)
SMALL = DiffusionConfig(down_dims=(16, 32), diffusion_step_embed_dim=16, num_inference_steps=4)


def _obs(policy: DiffusionPolicy, batch: int, seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {
        k: rng.uniform(-1, 1, (batch, d)).astype(np.float32) for k, d in policy.obs_dims.items()
    }


def _rollout(policy: DiffusionPolicy, batch: int, steps: int) -> np.ndarray:
    policy.reset(batch)
    return np.stack([policy.act(_obs(policy, batch, t)) for t in range(steps)])


def test_protocol_shapes_and_receding_horizon(monkeypatch):
    policy = random_policy(SMALL)
    assert isinstance(policy, Policy)
    calls = []
    original = policy.predict_chunk
    monkeypatch.setattr(policy, "predict_chunk", lambda envs: calls.append(envs) or original(envs))
    actions = _rollout(policy, batch=3, steps=17)
    assert actions.shape == (17, 3, 10) and actions.dtype == np.float32
    assert len(calls) == 3  # steps 0, 8, 16 with Ta = 8
    policy.reset_envs([1])
    policy.act(_obs(policy, 3, 0))
    assert calls[-1].tolist() == [1]
    with pytest.raises(InvalidArgumentError):
        policy.act(_obs(policy, 2, 0))


def test_first_observation_is_repeated():
    policy = random_policy(SMALL)
    policy.reset(2)
    obs = _obs(policy, 2, 0)
    policy.act(obs)
    assert torch.equal(policy._history.state[:, 0], policy._history.state[:, 1])
    policy.act(_obs(policy, 2, 1))
    assert not torch.equal(policy._history.state[:, 0], policy._history.state[:, 1])


@pytest.mark.parametrize("batch_invariant", [True, False])
def test_noise_per_env_is_independent_of_batch(batch_invariant):
    policy = random_policy(SMALL)
    policy.batch_invariant = batch_invariant  # False: one batched call (equal to round-off)
    alone = _rollout(policy, batch=1, steps=9)[:, 0]
    policy.reset(3)
    obs_seq = [_obs(policy, 3, t) for t in range(9)]
    for t in range(9):
        obs_seq[t] = {k: v.copy() for k, v in obs_seq[t].items()}
        for k in obs_seq[t]:
            obs_seq[t][k][0] = _obs(policy, 1, t)[k][0]
    batched = np.stack([policy.act(o) for o in obs_seq])[:, 0]
    np.testing.assert_allclose(batched, alone, atol=1e-5)


def test_seed_envs_makes_noise_follow_the_episode():
    policy = random_policy(SMALL)
    obs = _obs(policy, 2, 0)
    swapped = {k: v[::-1].copy() for k, v in obs.items()}
    policy.reset(2)
    policy.seed_envs([11, 22])
    first = policy.act(obs)
    policy.reset(2)
    policy.seed_envs([22, 11])
    second = policy.act(swapped)
    np.testing.assert_allclose(second[::-1], first, atol=1e-5)
    with pytest.raises(InvalidArgumentError):
        policy.seed_envs([1])


def test_finish_envs_samples_only_live_envs(monkeypatch):
    policy = random_policy(SMALL)
    calls = []
    original = policy.predict_chunk
    monkeypatch.setattr(policy, "predict_chunk", lambda envs: calls.append(envs) or original(envs))
    policy.reset(3)
    first = policy.act(_obs(policy, 3, 0))
    policy.finish_envs([1])
    for t in range(1, 9):
        actions = policy.act(_obs(policy, 3, t))
    assert [c.tolist() for c in calls] == [[0, 1, 2], [0, 2]]  # step 8 replans live envs only
    last_of_chunk = policy._queue[1, -1]
    np.testing.assert_array_equal(actions[1], last_of_chunk)  # finished env repeats its last
    assert not np.array_equal(actions[0], first[0])
    policy.reset_envs([1])
    policy.act(_obs(policy, 3, 9))
    assert calls[-1].tolist() == [1]


def test_checkpoint_round_trip_identical_actions(tmp_path):
    policy = random_policy(SMALL, seed=3)
    policy.meta = {"train_step": 5}
    policy.save(tmp_path / "ckpt")
    loaded = DiffusionPolicy.load(tmp_path / "ckpt")
    assert loaded.cfg == SMALL and loaded.obs_dims == policy.obs_dims
    assert loaded.meta["train_step"] == 5
    np.testing.assert_array_equal(_rollout(loaded, 4, 10), _rollout(policy, 4, 10))
    other_seed = DiffusionPolicy.load(tmp_path / "ckpt", seed=1)
    assert not np.array_equal(_rollout(other_seed, 4, 1), _rollout(policy, 4, 1))


def test_binary_gripper_executes_the_sign_of_the_sample():
    """binary_gripper: same samples, the gripper channel snapped to -1 / +1 (the others
    untouched); off, the untrained net's samples lie between (the case that matters)."""
    from dataclasses import replace

    plain = random_policy(replace(SMALL, binary_gripper=False), seed=4)
    snapped = random_policy(replace(SMALL, binary_gripper=True), seed=4)
    a, b = _rollout(plain, 6, 9), _rollout(snapped, 6, 9)
    grip_plain, grip_snapped = a[..., 9], b[..., 9]
    assert np.mean(np.abs(grip_plain) < 0.9) > 0.3
    np.testing.assert_array_equal(grip_snapped, np.where(grip_plain > 0.0, 1.0, -1.0))
    np.testing.assert_array_equal(a[..., :9], b[..., :9])


def test_binary_gripper_must_be_a_bool():
    with pytest.raises(InvalidArgumentError, match="binary_gripper"):
        DiffusionConfig.from_dict({"binary_gripper": "yes"})


def _corrupt_model(path):
    (path / "model.safetensors").write_bytes(b"\x00garbage")


def _truncate_model(path):
    data = (path / "model.safetensors").read_bytes()
    (path / "model.safetensors").write_bytes(data[: len(data) // 2])


def _bad_config(path):
    (path / "config.json").write_text("{not json")


def _wrong_shape(path):
    cfg = json.loads((path / "config.json").read_text())
    cfg["down_dims"] = [16, 64]
    (path / "config.json").write_text(json.dumps(cfg))


def _missing_file(path):
    (path / "normalizer.safetensors").unlink()


def _bad_meta(path):
    (path / "meta.json").write_text(json.dumps({"obs_dims": {}}))


@pytest.mark.parametrize(
    "damage", [_corrupt_model, _truncate_model, _bad_config, _wrong_shape, _missing_file, _bad_meta]
)
def test_corrupt_checkpoint_raises(tmp_path, damage):
    random_policy(SMALL).save(tmp_path)
    damage(tmp_path)
    with pytest.raises(CheckpointError) as info:
        DiffusionPolicy.load(tmp_path)
    assert "\n" not in str(info.value)


def test_missing_checkpoint_raises(tmp_path):
    with pytest.raises(CheckpointError, match="missing model.safetensors"):
        DiffusionPolicy.load(tmp_path / "nope")


def test_measure_inference_reports_costs():
    cost = measure_inference(random_policy(SMALL), batch_size=4, cycles=1)
    assert cost.ms_per_replan > 0 and cost.ms_per_env_step > 0
    assert cost.ms_per_env_step == pytest.approx(cost.ms_per_batched_step / 4)


def test_bench_prints_policy_cost_next_to_env_cost(capsys, monkeypatch):
    """One run prints the DDIM cost per env step, the env's step cost and their ratio."""
    import impact_experiments.dp_inference_cost as bench

    monkeypatch.setattr(bench, "random_policy", lambda: random_policy(SMALL))
    real = bench.measure_env_step
    monkeypatch.setattr(bench, "measure_env_step", lambda env_id: real(env_id, steps=3))
    bench_main(["--batch", "4", "--cycles", "1"])
    out = capsys.readouterr().out
    assert "IMPACT/Hammer-v1 env.step" in out and "policy cost / env cost:" in out


def _shipped_policy() -> DiffusionPolicy:
    from impact_eval.methods import checkpoint_dir

    return DiffusionPolicy.load(checkpoint_dir("IMPACT/Hammer-v1", "vanilla"))


@pytest.mark.parametrize("batch,slot,threads", [(3, 2, 1), (5, 0, 2), (17, 9, 1)])
def test_actions_are_bit_identical_for_any_batch_slot_and_thread_count(batch, slot, threads):
    """An env's actions are a function of its own observations and seed, to the last bit:
    alone, or in any slot of a larger batch (other envs see other observations), whatever
    the caller's torch thread count (torch rounds batched and multi-threaded kernels
    differently, so the policy denoises each env alone on one thread)."""
    policy = _shipped_policy()
    steps = 9  # two replanning steps (Ta = 8)
    policy.reset(1)
    policy.seed_envs([1234])
    alone = np.stack([policy.act(_obs(policy, 1, t)) for t in range(steps)])[:, 0]
    before = torch.get_num_threads()
    torch.set_num_threads(threads)
    try:
        policy.reset(batch)
        seeds = [1000 + i for i in range(batch)]
        seeds[slot] = 1234
        policy.seed_envs(seeds)
        rows = []
        for t in range(steps):
            obs = _obs(policy, batch, 100 + t)
            for k in obs:
                obs[k][slot] = _obs(policy, 1, t)[k][0]
            rows.append(policy.act(obs)[slot])
    finally:
        torch.set_num_threads(before)
    np.testing.assert_array_equal(np.stack(rows), alone)
    assert torch.get_num_threads() == before  # the caller's thread count is restored


def test_frozen_unet_equals_the_eager_network_or_falls_back(monkeypatch):
    from impact_envs.policies.diffusion import inference

    policy = _shipped_policy()
    cond_dim = policy.cfg.n_obs_steps * policy.normalizer.obs.dim
    args = (policy.net, policy.cfg.horizon, 10, cond_dim)
    with torch.inference_mode():
        fast = inference.frozen_unet(*args)
        gen = torch.Generator().manual_seed(7)
        sample, cond = torch.randn(1, policy.cfg.horizon, 10, generator=gen), torch.randn(
            1, cond_dim, generator=gen)
        for step in (torch.tensor(3), torch.tensor(80)):
            assert torch.equal(fast(sample, step, cond), policy.net(sample, step, cond))

        def broken(*_args, **_kwargs):
            raise RuntimeError("no TorchScript here")

        monkeypatch.setattr(torch.jit, "trace", broken)
        assert inference.frozen_unet(*args) is policy.net


@pytest.mark.parametrize("field,value,message", [
    ("horizon", "16", "field horizon: '16'; valid: an integer"),
    ("lr", "1e-4", "field lr: '1e-4'; valid: a number"),
    ("down_dims", [16, "32"], "field down_dims: [16, '32']; valid: a list of integers"),
    ("binary_gripper", 1, "field binary_gripper: 1; valid: true or false"),
    ("obs_keys", "ee_pos", "field obs_keys: 'ee_pos'; valid: a list of strings"),
    ("num_inference_steps", 4.0, "field num_inference_steps: 4.0"),
    ("betas", None, "field betas: None; valid: a list of numbers"),
])
def test_checkpoint_config_of_a_wrong_type_names_the_field(tmp_path, field, value, message):
    random_policy(SMALL).save(tmp_path)
    cfg = json.loads((tmp_path / "config.json").read_text())
    cfg[field] = value
    (tmp_path / "config.json").write_text(json.dumps(cfg))
    with pytest.raises(CheckpointError) as info:
        DiffusionPolicy.load(tmp_path)
    assert message in str(info.value) and "\n" not in str(info.value)
