"""The contract of every ``impact-*`` command on bad input, as one table: exit code 2, one
stderr line ``PROG: error: ...`` naming what is wrong, no traceback, and no file left behind
(the temporary directory and the output path are exactly as before)."""

from __future__ import annotations

import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import zarr
from fixtures.eval_fake import corrupt_checkpoint, sweep_args
from fixtures.fake_reach import collect_demos

from impact_eval import bench, cli
from impact_eval.methods import CHECKPOINTS_ENV_VAR
from impact_experiments import adaptation
from impact_learn import collect as collect_module
from impact_learn import train as train_module

HAMMER = ("--env", "IMPACT/Hammer-v1")

# name: (command, arguments replacing / added to the command's valid base, message part)
CASES: dict[str, tuple[str, tuple[str, ...], str]] = {
    # impact-eval (base: a valid fake-env sweep)
    "eval unknown env": ("eval", ("--env", "IMPACT/Nope-v0"), "valid choices"),
    "eval unknown method": ("eval", ("--method", "fake_fast,dp"), "valid choices: scripted"),
    "eval unknown parameter": ("eval", ("--param", "friction"), "valid choices: object_mass"),
    "eval malformed grid": ("eval", ("--masses", "1:0.5"), "malformed grid"),
    "eval rejected value": ("eval", ("--masses", "0,2"), "object_mass=0.0 rejected"),
    "eval nan value": ("eval", ("--masses", "nan"), "'nan' is not finite"),
    "eval zero episodes": ("eval", ("--episodes", "0"), "--episodes must be >= 1"),
    "eval episodes not a number": ("eval", ("--episodes", "five"), "invalid int value"),
    "eval zero workers": ("eval", ("--workers", "0"), "--workers"),
    "eval missing checkpoint": ("eval", ("--method", "vanilla_dp"), "no vanilla checkpoint"),
    "eval corrupt checkpoint": ("eval", ("--method", "impact"), "cannot load vanilla checkpoint"),
    "eval corrupt sb3 zip": ("eval", ("--method", "sb3:{tmp}/ppo.zip", "--trust-sb3"),
                             "cannot load SB3 checkpoint"),
    "eval sb3 zip without opt-in": ("eval", ("--method", "sb3:{tmp}/ppo.zip"), "--trust-sb3"),
    "eval missing sb3 zip": ("eval", ("--method", "sb3:{tmp}/nope.zip"), "does not exist"),
    "eval out under a file": ("eval", ("--out", "{tmp}/afile/sub"), "not writable"),
    "eval out on /proc": ("eval", ("--out", "/proc/impact-eval-test"), "not writable"),
    "eval unknown option": ("eval", ("--mases", "1"), "unrecognized arguments"),
    "eval unknown controller field": ("eval", ("--controller-set", "internal_model.lr=1"),
                                      "unknown field 'lr' of controller config section"),
    "eval no scripted expert": ("eval", ("--method", "scripted"),
                                "no scripted expert for 'ImpactTest/Fake-v0'"),
    "eval torque above the FR3": (
        "eval", ("--controller-set", "limits.torque_max_nm=1000,87,87,87,12,12,12"),
        "limits.torque_max_nm[0]=1000 > 87 Nm: above the FR3's hardware limits"),
    "eval torque rate above the FR3": (
        "eval", ("--controller-set", "limits.torque_rate_max_nm_per_s=5000"),
        "pass --beyond-hardware-limits"),
    "eval report of a missing dir": ("report", ("{tmp}/nothing",), "nothing"),
    # impact-collect (base: one Hammer demo into {tmp}/x.zarr)
    "collect unknown env": ("collect", ("--env", "Foo/Bar-v0"),
                            "valid: IMPACT/Hammer-v1, IMPACT/Hammer-v2"),
    "collect unknown controller": ("collect", ("--controller", "pid"),
                                   "valid choices: impedance, impact"),
    "collect malformed range": ("collect", ("--mass-range", "3"), "LO:HI"),
    "collect unknown compensation": ("collect", ("--compensation", "psychic"),
                                     "valid choices: none, closed_loop, privileged"),
    "collect compensation of calligraphy": (
        "collect", ("--env", "IMPACT/Calligraphy-v1", "--compensation", "closed_loop"),
        "compensation='none'"),
    "collect compensation of disturbance": (
        "collect", ("--env", "IMPACT/Disturbance-v1", "--compensation", "closed_loop"),
        "compensation='none'"),
    "collect mass list out of range": ("collect", ("--mass-list", "50,1"),
                                       "object_mass=50.0 out of range"),
    "collect mass range out of range": ("collect", ("--mass-range", "1:100"),
                                        "object_mass=100.0 out of range"),
    "collect zero attempts": ("collect", ("--max-attempts", "0"), "--max-attempts must be >= 1"),
    "collect negative seed": ("collect", ("--seed", "-1"), "--seed must be >= 0"),
    "collect zero episodes": ("collect", ("--episodes", "0"), "--episodes must be >= 1, got 0"),
    "collect zero envs": ("collect", ("--n-envs", "0"), "--n-envs must be >= 1, got 0"),
    "collect two mass options": ("collect", ("--mass", "1", "--mass-list", "1,2"),
                                 "not allowed with argument"),
    "collect missing env": ("collect", ("--env",), "expected one argument"),
    "collect unknown obs mode": ("collect", ("--obs-mode", "depth"),
                                 "valid choices: state, rgb, rgbd, state+rgb"),
    "collect unknown camera": ("collect", ("--obs-mode", "rgb", "--cameras", "top"),
                               "valid choices: front, side, overview, wrist"),
    "collect image too large": ("collect", ("--obs-mode", "rgb", "--image-width", "4000"),
                                "at most 640x480"),
    # impact-train (base: 2 steps on a small fake store)
    "train text file as data": ("train", ("--data", "{tmp}/t.txt"),
                                "is not a readable demonstration store"),
    "train empty dir as data": ("train", ("--data", "{tmp}/empty"),
                                "is not a readable demonstration store"),
    "train missing data": ("train", ("--data", "{tmp}/missing.zarr"), "dataset"),
    "train store holding nan": ("train", ("--data", "{nan_store}",), "non-finite values"),
    "train garbage config": ("train", ("--config", "{tmp}/g.json"), "cannot read config"),
    "train list config": ("train", ("--config", "{tmp}/l.json"), "must be a JSON object"),
    "train missing config": ("train", ("--config", "{tmp}/nope.json"), "cannot read config"),
    "train negative threads": ("train", ("--threads", "-1"), "--threads must be >= 1"),
    "train out is a file": ("train", ("--out", "{tmp}/t.txt"), "is a file; give a directory"),
    "train zero steps": ("train", ("--steps", "0"), "--steps must be >= 1, got 0"),
    "train zero val every": ("train", ("--val-every", "0"), "--val-every must be >= 1"),
    "train steps not a number": ("train", ("--steps", "many"), "invalid int value"),
    # impact-bench
    "bench zero steps": ("bench", ("--steps", "0"), "need --steps >= 2"),
    "bench zero repeat": ("bench", ("--repeat", "0"), "--repeat >= 1"),
    "bench nan mass": ("bench", ("--mass", "nan"), "object_mass=nan out of range"),
    "bench negative mass": ("bench", ("--mass", "-1"), "object_mass=-1.0 out of range"),
    "bench unknown env": ("bench", ("--env", "IMPACT/Nope-v0"), "invalid choice"),
    # impact-protocol (base: --out {tmp}/out)
    "protocol zero repeats": ("protocol", ("--repeats", "0"), "--repeats must be >= 1"),
    "protocol negative mass": ("protocol", ("--masses", "-3"), "out of range"),
    "protocol nan mass": ("protocol", ("--masses", "nan"), "out of range"),
    "protocol mass not a number": ("protocol", ("--masses", "2.5,abc"), "could not convert"),
    "protocol mass above range": ("protocol", ("--masses", "2.5,99"), "out of range"),
    "protocol unknown env": ("protocol", ("--env", "IMPACT/Nope-v0"), "valid choices"),
    "protocol negative hold": ("protocol", ("--hold-s", "-1"), "hold"),
    "protocol unknown robot field": ("protocol", ("--robot-set", "nope=1"),
                                     "valid: FIELD=VALUE with FIELD one of"),
    "protocol unknown realism": ("protocol", ("--robot-set", "realism=mars"),
                                 "valid choices: ideal, fr3"),
}


def _with(base: list[str], changes: tuple[str, ...]) -> list[str]:
    """``base`` with each ``--flag value`` of ``changes`` replaced or appended."""
    args, i = list(base), 0
    while i < len(changes):
        flag = changes[i]
        has_value = i + 1 < len(changes) and not changes[i + 1].startswith("--")
        if has_value and flag in args:
            args[args.index(flag) + 1] = changes[i + 1]
        else:
            args += [flag, changes[i + 1]] if has_value else [flag]
        i += 2 if has_value else 1
    return args


def _invoke(main: Callable, argv: list[str]) -> int:
    """Exit code of an entry point that returns it or raises SystemExit."""
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    return 0 if code is None else code


def _command(name: str, tmp: Path, changes: tuple[str, ...]) -> tuple[Callable, list[str], str]:
    """(entry point, argv, prog) of one case."""
    if name == "report":
        return cli.main, ["report", *changes], "impact-eval"
    base = {
        "eval": sweep_args(tmp / "out", "--workers", "1"),
        "collect": [*HAMMER, "--out", str(tmp / "x.zarr"), "--episodes", "1", "--no-progress"],
        "train": ["--data", "{store}", "--out", str(tmp / "run"), "--steps", "2",
                  "--no-progress"],
        "bench": [],
        "protocol": ["--out", str(tmp / "out")],
    }[name]
    main = {"eval": cli.main, "collect": collect_module.main, "train": train_module.main,
            "bench": bench.main, "protocol": adaptation.main}[name]
    return main, _with(base, changes), {"eval": "impact-eval"}.get(name, f"impact-{name}")


@pytest.fixture(scope="module")
def stores(tmp_path_factory) -> dict[str, str]:
    """A small valid demonstration store and a copy holding one NaN."""
    root = tmp_path_factory.mktemp("stores")
    collect_demos(root / "ok.zarr", param=0.2)
    collect_demos(root / "nan.zarr", param=0.2)
    zarr.open_group(str(root / "nan.zarr"), mode="r+")["data/ee_pos"][3, 1] = np.nan
    return {"{store}": str(root / "ok.zarr"), "{nan_store}": str(root / "nan.zarr")}


def _tree(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


@pytest.mark.parametrize("case", list(CASES))
def test_bad_input_is_one_line_exit_2_and_leaves_nothing(case, stores, tmp_path, capsys,
                                                         monkeypatch):
    assert len(CASES) >= 40
    (tmp_path / "afile").write_text("x")
    (tmp_path / "t.txt").write_text("hi")
    (tmp_path / "empty").mkdir()
    (tmp_path / "g.json").write_text("{garbage")
    (tmp_path / "l.json").write_text("[1, 2]")
    with zipfile.ZipFile(tmp_path / "ppo.zip", "w") as z:
        z.writestr("data", "garbage")
    checkpoints = corrupt_checkpoint(tmp_path / "ckpt")
    monkeypatch.setenv(CHECKPOINTS_ENV_VAR, str(checkpoints if case != "eval missing checkpoint"
                                                else tmp_path / "none"))
    monkeypatch.delenv("IMPACT_TRUST_SB3", raising=False)
    name, changes, message = CASES[case]
    main, argv, prog = _command(name, tmp_path, changes)
    subst = {"{tmp}": str(tmp_path), **stores}
    for key, value in subst.items():
        argv = [a.replace(key, value) for a in argv]
        message = message.replace(key, value)
    before = _tree(tmp_path)
    assert _invoke(main, argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"{prog}: error:"), err
    assert message in err and "Traceback" not in err, err
    assert _tree(tmp_path) == before
    assert not Path("/proc/impact-eval-test").exists()
