"""Pre-flight checks: everything is validated before the output directory is touched.

``prepare`` turns parsed CLI arguments into a ``Plan`` or raises a one-line ``ImpactError``:
grid, methods, env id, parameter name, parameter values (one reset each), output directory,
resume state, and finally one build of every method's policy (checkpoints load).
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path

from impact_control.config import ControllerConfig, beyond_hardware_limits
from impact_control.errors import ImpactError, InvalidArgumentError
from impact_control.overrides import apply_overrides
from impact_envs.envs.options import apply_robot_overrides
from impact_envs.parallel import check_executor
from impact_eval import csvio, runinfo
from impact_eval.bins import bin_param_name, parse_bins
from impact_eval.envs import (
    EnvInfo,
    check_env_id,
    check_param,
    describe_env,
    make_env,
    method_env,
    precompile_kernels,
    probe_values,
)
from impact_eval.grid import episode_seed, format_value, parse_grid
from impact_eval.methods import MethodSpec, resolve_method
from impact_eval.report import EPISODES_CSV
from impact_eval.sweep import SweepConfig


@dataclass(frozen=True)
class SweepRequest:
    """The sweep as asked for on the command line (already type-converted by argparse)."""

    env_id: str
    methods: str
    grid: str | None
    param: str | None
    episodes: int
    out: Path
    workers: int
    envs_per_worker: int
    seed: int
    resume: bool
    controller_overrides: tuple[str, ...] = ()
    robot_overrides: tuple[str, ...] = ()
    """``--robot-set FIELD=VALUE``: ``RobotOptions`` fields on every method's robot."""
    extend: bool = False
    """``--extend``: resume, and let methods and grid values grow (``check_resumable``)."""
    video_episodes: int = 0
    """``--video K``: the first K episodes of every cell as MP4 (``OUT/videos``)."""
    beyond_hardware_limits: bool = False
    """Allow ``--controller-set`` limits above the FR3's torque and torque-rate limits."""
    executor: str = "local"
    """``--executor``: ``local`` or ``ray``."""
    ray_address: str | None = None
    """``--ray-address`` (``--executor ray`` only)."""
    mass_bins: str | None = None
    """``--mass-bins LO-HI,...`` instead of ``grid`` (``bins.py``): each episode draws the
    parameter in its bin."""


@dataclass(frozen=True)
class Plan:
    """A validated sweep: config for the workers, env facts, and the cells already done."""

    config: SweepConfig
    env: EnvInfo
    out: Path
    done: set[csvio.EpisodeKey]
    previous_run: dict | None
    identity: runinfo.RunIdentity
    """Written to ``identity.json`` before the first row (``runinfo.IDENTITY_JSON``)."""


def parse_methods(text: str) -> list[MethodSpec]:
    """Comma list of method names -> specs (unknown or repeated names are bad input)."""
    names = [m.strip() for m in text.split(",")]
    if any(not n for n in names):
        raise InvalidArgumentError(f"malformed --method {text!r}: empty item")
    if len(set(names)) != len(names):
        raise InvalidArgumentError(f"malformed --method {text!r}: repeated method")
    return [resolve_method(n) for n in names]


def check_numbers(req: SweepRequest) -> None:
    """Counts must be positive and the seed non-negative."""
    for name, value, low in (
        ("--episodes", req.episodes, 1),
        ("--workers", req.workers, 1),
        ("--envs-per-worker", req.envs_per_worker, 1),
        ("--seed", req.seed, 0),
    ):
        if value < low:
            raise InvalidArgumentError(f"{name} must be >= {low}, got {value}")


def check_out_dir(out: Path) -> None:
    """``out`` must be a directory or creatable, on a writable filesystem (probed, no residue)."""
    if out.exists() and not out.is_dir():
        raise InvalidArgumentError(f"--out {out} exists and is not a directory")
    anchor = out
    while not anchor.exists() and anchor != anchor.parent:
        anchor = anchor.parent
    try:
        if not anchor.is_dir():
            raise NotADirectoryError(f"{anchor} is not a directory")
        with tempfile.TemporaryFile(dir=anchor):
            pass
    except OSError as exc:
        raise InvalidArgumentError(f"--out {out} is not writable: {exc}") from None


def load_done(req: SweepRequest, env: EnvInfo, values: list[float],
              row_param_name: str) -> set[csvio.EpisodeKey]:
    """Cells already in ``episodes.csv`` (``--resume``), checked against this grid's seeds."""
    path = req.out / EPISODES_CSV
    if not path.exists() or path.stat().st_size == 0:  # 0 bytes: the writer starts it afresh
        return set()
    if not (req.resume or req.extend):
        raise InvalidArgumentError(
            f"{path} already exists; pass --resume (or --extend) to continue it or choose "
            "another --out"
        )
    index = {format_value(v): i for i, v in enumerate(values)}
    done = set()
    for row in csvio.read_rows(path):
        key = csvio.row_key(row)
        if row["env_id"] != env.env_id or row["param_name"] != row_param_name:
            raise InvalidArgumentError(
                f"cannot resume: {path} holds {row['env_id']}/{row['param_name']} episodes"
            )
        vi = index.get(key[1])
        try:
            seed = int(row["seed"])
        except ValueError:
            raise InvalidArgumentError(
                f"cannot resume: {path} has a row with seed {row['seed']!r} (episode {key}); "
                "fix or delete that row") from None
        if vi is not None and seed != episode_seed(req.seed, vi, key[2]):
            raise InvalidArgumentError(
                f"cannot resume: seeds in {path} do not match this grid and --seed "
                "(was the grid changed?); use the original arguments or another --out"
            )
        done.add(key)
    return done


def _inspect_env(req: SweepRequest, specs: list[MethodSpec], values: list[float]) -> EnvInfo:
    """Build one env per controller, read its facts and probe the parameter values."""
    envs = {}
    try:
        for spec in specs:
            if spec.env_key not in envs:
                envs[spec.env_key] = make_env(
                    req.env_id, spec.controller, req.controller_overrides, spec.preset,
                    observation=spec.observation, robot=spec.robot,
                    robot_overrides=req.robot_overrides)
            if spec.carry:
                check_carries(spec, envs[spec.env_key], req.env_id)
        first = next(iter(envs.values()))
        info = describe_env(first, req.param)
        check_param(info, req.param)
        probe_values(first, info.param_name, values)
        for env in envs.values():
            precompile_kernels(env)
        return info
    finally:
        for env in envs.values():
            env.close()


def check_carries(spec: MethodSpec, env: object, env_id: str) -> None:
    """A carried method (``MethodSpec.carry``) needs an env that can carry its controller's
    state into the next episode (``ImpactEnv.carry_controller``)."""
    base = getattr(env, "unwrapped", env)
    if not all(callable(getattr(base, name, None))
               for name in ("carry_controller", "controller_carry")):
        raise InvalidArgumentError(
            f"method {spec.name!r} carries the controller state across a cell's episodes, but "
            f"{env_id} cannot (no carry_controller / controller_carry); valid: an IMPACT env")


def _build_policies(req: SweepRequest, specs: list[MethodSpec], env_id: str) -> None:
    """Build each method's policy once (checkpoints load, experts exist), then drop it."""
    for spec in specs:
        env = method_env(req.env_id, spec)
        try:
            spec.build(env_id, env)
        except ImpactError:
            raise
        except Exception as exc:  # noqa: BLE001 - any build failure is reported in one line
            msg = " ".join(str(exc).split())[:160]
            raise InvalidArgumentError(
                f"cannot build method {spec.name!r} for {env_id}: {type(exc).__name__}: {msg}"
            ) from None
        finally:
            env.close()


def sweep_values(req: SweepRequest) -> tuple[list[float], tuple[float, ...]]:
    """(values, bin upper edges): the grid's values and no edges, or with ``--mass-bins``
    the bins' lower edges and their upper edges."""
    if req.mass_bins is None:
        return parse_grid(req.grid), ()
    if req.grid is not None:
        raise InvalidArgumentError(
            "give either a grid (--masses/--param-values) or --mass-bins, not both")
    bins = parse_bins(req.mass_bins)
    return [b.lo for b in bins], tuple(b.hi for b in bins)


def prepare(req: SweepRequest) -> Plan:
    """Validate a sweep request without creating any file."""
    check_numbers(req)
    check_executor(req.executor, req.ray_address)
    if req.controller_overrides:  # bad overrides fail here, before any env is built
        overridden = apply_overrides(ControllerConfig(), req.controller_overrides)
        above = beyond_hardware_limits(overridden.limits)
        if above and not req.beyond_hardware_limits:
            raise InvalidArgumentError(
                f"{'; '.join(above)}: above the FR3's hardware limits (87 Nm x4, 12 Nm x3, "
                "1000 Nm/s); pass --beyond-hardware-limits to run it anyway (run.json records it)")
    if req.robot_overrides:  # bad robot fields fail here too, in one line
        apply_robot_overrides(None, req.robot_overrides).resolved_realism()
    if req.video_episodes < 0:
        raise InvalidArgumentError(f"--video must be >= 0, got {req.video_episodes}")
    if req.video_episodes:  # an encoder and a GL context, before anything is written
        from impact_eval.video import require_video

        require_video()
    values, highs = sweep_values(req)
    check_env_id(req.env_id)  # imports the env's module, which may register methods too
    specs = parse_methods(req.methods)
    info = _inspect_env(req, specs, sorted({*values, *highs}))  # a bin's edges: both accepted
    check_out_dir(req.out)
    continuing = req.resume or req.extend
    previous = runinfo.read_run_json(req.out) if continuing else None
    identity = runinfo.RunIdentity(
        env=req.env_id, seed=req.seed, param_name=info.param_name,
        controller_overrides=tuple(req.controller_overrides),
        robot_overrides=tuple(req.robot_overrides),
        methods=tuple(s.name for s in specs), values=tuple(values), episodes=req.episodes,
        method_controllers={s.name: s.settings for s in specs}, bin_highs=highs)
    if continuing:
        csv_path = req.out / EPISODES_CSV
        has_rows = csv_path.exists() and bool(csvio.read_rows(csv_path))
        runinfo.check_resumable(runinfo.recorded_identity(req.out), identity,
                                extend=req.extend, has_rows=has_rows)
    row_param = bin_param_name(info.param_name) if highs else info.param_name
    done = load_done(req, info, values, row_param)
    _build_policies(req, specs, info.env_id)
    config = SweepConfig(
        env_id=req.env_id,
        canonical_env_id=info.env_id,
        param_name=info.param_name,
        policy_dt=info.policy_dt,
        methods=tuple(s.name for s in specs),
        values=tuple(values),
        episodes=req.episodes,
        seed=req.seed,
        workers=req.workers,
        envs_per_worker=req.envs_per_worker,
        controller_overrides=tuple(req.controller_overrides),
        robot_overrides=tuple(req.robot_overrides),
        video_episodes=req.video_episodes,
        video_dir=str(req.out / "videos"),
        executor=req.executor,
        ray_address=req.ray_address,
        bin_highs=highs,
    )
    return Plan(config=config, env=info, out=req.out, done=done, previous_run=previous,
                identity=identity)
