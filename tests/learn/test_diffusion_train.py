"""Training loop: outputs, held-out log, bit-exact resume, CLI."""

from __future__ import annotations

import csv
import json

import pytest
import torch
from fixtures.reach_demos import write_dataset
from safetensors.torch import load_file

from impact_control.errors import InvalidArgumentError
from impact_envs.policies.diffusion.config import DiffusionConfig
from impact_envs.policies.diffusion.policy import DiffusionPolicy
from impact_learn import train as train_module
from impact_learn.train import RunOptions, lr_at, train

torch.set_num_threads(1)
CFG = DiffusionConfig(
    down_dims=(16, 32), diffusion_step_embed_dim=16, num_inference_steps=4, batch_size=8
)
@pytest.fixture
def data_path(tmp_path):
    path = tmp_path / "demo.zarr"
    write_dataset(path)
    return path


def _opts(steps: int, resume: bool = False) -> RunOptions:
    return RunOptions(
        steps=steps,
        checkpoint_every=2,
        val_every=2,
        val_fraction=0.2,
        resume=resume,
        progress=False,
    )


def _rows(path):
    with (path / "log.csv").open() as f:
        return [{k: v for k, v in r.items() if k != "elapsed_s"} for r in csv.DictReader(f)]


def _state_tensors(out):
    return load_file(str(out / "train_state" / "tensors.safetensors"))


def _assert_same_run(a, b):
    ta, tb = _state_tensors(a), _state_tensors(b)
    assert ta.keys() == tb.keys()
    for key in ta:
        assert torch.equal(ta[key], tb[key]), key
    assert _rows(a) == _rows(b)


def test_train_outputs_and_log(data_path, tmp_path):
    out = tmp_path / "run"
    state = train(CFG, data_path, out, _opts(4))
    assert state.step == 4
    rows = _rows(out)
    assert [int(r["step"]) for r in rows] == [2, 4]
    assert all(float(r["val_action_mse"]) >= 0 and float(r["val_loss"]) > 0 for r in rows)
    policy = DiffusionPolicy.load(out / "policy")
    assert policy.meta["train_step"] == 4 and policy.meta["dataset"]["n_episodes"] == 5
    assert (out / "best" / "model.safetensors").is_file()
    ema = {k[4:]: v for k, v in _state_tensors(out).items() if k.startswith("ema.")}
    exported = load_file(str(out / "policy" / "model.safetensors"))
    assert all(torch.equal(exported[k], ema[k]) for k in exported)
    with pytest.raises(InvalidArgumentError, match="--resume"):
        train(CFG, data_path, out, _opts(6))


def test_resume_is_bit_exact(data_path, tmp_path):
    train(CFG, data_path, tmp_path / "full", _opts(4))
    train(CFG, data_path, tmp_path / "split", _opts(2))
    train(CFG, data_path, tmp_path / "split", _opts(4, resume=True))
    _assert_same_run(tmp_path / "full", tmp_path / "split")


def test_resume_with_more_steps_records_the_schedule_and_fewer_is_refused(data_path, tmp_path):
    out = tmp_path / "run"
    train(CFG, data_path, out, _opts(2))

    def files() -> dict[str, bytes]:
        return {str(f.relative_to(out)): f.read_bytes() for f in out.rglob("*") if f.is_file()}

    before = files()
    with pytest.raises(InvalidArgumentError, match=r"is at step 2; valid: --steps >= 2") as err:
        train(CFG, data_path, out, _opts(1, resume=True))
    assert "\n" not in str(err.value) and files() == before  # nothing written
    train(CFG, data_path, out, _opts(4, resume=True))
    assert DiffusionPolicy.load(out / "policy").meta["schedule"] == [
        {"from_step": 0, "steps": 2}, {"from_step": 2, "steps": 4}]


def test_resume_after_interruption(data_path, tmp_path, monkeypatch):
    cfg = DiffusionConfig(**{**CFG.to_dict(), "lr_warmup_steps": 1})  # cosine part matters
    train(cfg, data_path, tmp_path / "full", _opts(6))
    original = train_module.train_step

    def crash_at_step_3(state, *args):
        if state.step == 3:
            raise KeyboardInterrupt
        return original(state, *args)

    monkeypatch.setattr(train_module, "train_step", crash_at_step_3)
    with pytest.raises(KeyboardInterrupt):
        train(cfg, data_path, tmp_path / "cut", _opts(6))
    monkeypatch.setattr(train_module, "train_step", original)
    train(CFG, data_path, tmp_path / "cut", _opts(6, resume=True))  # cfg read from the run
    _assert_same_run(tmp_path / "full", tmp_path / "cut")


def test_lr_schedule():
    cfg = DiffusionConfig(lr=1e-4, lr_warmup_steps=10)
    assert lr_at(cfg, 0, 100) == 0.0
    assert lr_at(cfg, 5, 100) == pytest.approx(5e-5)
    assert lr_at(cfg, 10, 100) == pytest.approx(1e-4)
    assert lr_at(cfg, 55, 100) == pytest.approx(5e-5)
    assert lr_at(cfg, 100, 100) == pytest.approx(0.0, abs=1e-12)


def test_cli(data_path, tmp_path, capsys):
    cfg_path = tmp_path / "cfg.json"
    CFG.to_json(cfg_path)
    out = tmp_path / "cli"
    argv = ["--data", str(data_path), "--out", str(out), "--steps", "2", "--batch-size", "4"]
    train_module.main([*argv, "--config", str(cfg_path), "--no-progress", "--val-every", "1"])
    assert "trained 2 steps" in capsys.readouterr().out
    saved = DiffusionConfig.from_json(out / "config.json")
    assert saved.batch_size == 4 and saved.down_dims == CFG.down_dims
    assert len(_rows(out)) == 2


def test_graded_gripper_demos_need_binary_gripper_off(tmp_path, capsys):
    """binary_gripper (default) would execute only the sign of a graded gripper command: refuse
    such demos with a one-line error naming the setting; with it off they train."""
    path = tmp_path / "graded.zarr"
    write_dataset(path, grip=0.5)
    with pytest.raises(SystemExit) as exc:
        train_module.main(["--data", str(path), "--out", str(tmp_path / "run"), "--steps", "2",
                           "--no-progress"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "binary_gripper" in err and err.count("\n") == 1
    config = tmp_path / "cfg.json"
    config.write_text(json.dumps({"down_dims": [16, 32], "batch_size": 8,
                                  "binary_gripper": False}))
    train_module.main(["--data", str(path), "--out", str(tmp_path / "run2"), "--steps", "2",
                       "--no-progress", "--config", str(config)])
    assert (tmp_path / "run2" / "policy" / "config.json").is_file()
