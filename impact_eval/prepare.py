"""Pre-flight checks: everything is validated before the output directory is touched.

``prepare`` turns a ``SweepSpec`` and its ``RunOptions`` into a ``Plan`` or raises a one-line
``ImpactError``: methods, env id, parameter name, parameter values (one reset each), output
directory, resume state, and finally one build of every method's policy (checkpoints load).
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

from impact_control.errors import ImpactError, InvalidArgumentError
from impact_envs.tasks.bins import bin_param_name, check_bin_param, draw_in_bin
from impact_eval import csvio, runinfo
from impact_eval.checkpoints import fingerprint, policy_checkpoint
from impact_eval.code_check import check_same_code
from impact_eval.envs import (
    EnvInfo,
    check_env_id,
    check_param,
    describe_env,
    make_env,
    method_env,
    precompile_kernels,
    probe_values,
    task_params,
)
from impact_eval.grid import episode_seed, format_value
from impact_eval.methods import MethodSpec, check_overrides_keep_flags, resolve_method
from impact_eval.report import EPISODES_CSV
from impact_eval.spec import RunOptions, SweepSpec
from impact_eval.sweep import SweepConfig


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


def resolve_methods(names: tuple[str, ...], robot_overrides: tuple[str, ...] = ()
                    ) -> list[MethodSpec]:
    """The spec's method names -> methods (an unknown name is one line naming the choices;
    so is a ``--robot-set`` that undoes a method's flag, ``check_overrides_keep_flags``)."""
    methods = [resolve_method(n) for n in names]
    for method in methods:
        check_overrides_keep_flags(method, robot_overrides)
    return methods


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


def load_done(spec: SweepSpec, options: RunOptions, env: EnvInfo,
              row_param_name: str) -> set[csvio.EpisodeKey]:
    """Cells already in ``episodes.csv`` (``--resume``): every row must be one of this run's
    cells, with this grid's seed and, in a bin, the mass its bin and seed draw
    (``check_row``); the first that is not is refused in one line."""
    path = options.out / EPISODES_CSV
    if not path.exists() or path.stat().st_size == 0:  # 0 bytes: the writer starts it afresh
        return set()
    if not (options.resume or options.extend):
        raise InvalidArgumentError(
            f"{path} already exists; pass --resume (or --extend) to continue it or choose "
            "another --out"
        )
    index = {format_value(v): i for i, v in enumerate(spec.values)}
    done = set()
    for line, row in enumerate(csvio.read_rows(path), start=2):
        if row["env_id"] != env.env_id or row["param_name"] != row_param_name:
            raise InvalidArgumentError(
                f"cannot resume: {path} holds {row['env_id']}/{row['param_name']} episodes"
            )
        problem = check_row(spec, row, index)
        if problem:
            raise InvalidArgumentError(
                f"cannot resume: {path} line {line} ({row['method']} @ {row['param_value']}, "
                f"episode {row['episode']}) is not a row of this run: {problem}; delete it, "
                "or use the original arguments or another --out")
        done.add(csvio.row_key(row))
    return done


def check_row(spec: SweepSpec, row: dict[str, str], index: dict[str, int]) -> str | None:
    """Why ``row`` of an existing ``episodes.csv`` is not one of ``spec``'s cells (None: it
    is): another method, value or bin, an episode index beyond ``spec.episodes``, another
    seed, or in a bin a ``drawn_mass_kg`` its bin and seed do not draw (``draw_in_bin``)."""
    method, value, episode = csvio.row_key(row)
    if method not in spec.methods:
        return f"method {method!r} is not among {', '.join(spec.methods)}"
    vi = index.get(value)
    if vi is None:
        kind = "bin lower edge" if spec.bin_highs else "value"
        return f"{kind} {row['param_value']} is not among {list(spec.values)}"
    if not 0 <= episode < spec.episodes:
        return f"episode {episode} is beyond --episodes {spec.episodes}"
    try:
        seed = int(row["seed"])
    except ValueError:
        return f"seed {row['seed']!r} is not an integer"
    if seed != episode_seed(spec.seed, vi, episode):
        return "its seed is not this grid's and --seed's (was the grid changed?)"
    if spec.bin_highs:
        return _check_draw(row["drawn_mass_kg"], spec.values[vi], spec.bin_highs[vi], seed)
    return None


def _check_draw(recorded: str, lo: float, hi: float, seed: int) -> str | None:
    """Why a bin row's ``drawn_mass_kg`` text is not the mass its bin and seed draw (None: it
    is, or the env reported no mass: ``nan``)."""
    try:
        mass = float(recorded)
    except ValueError:
        return f"drawn_mass_kg {recorded!r} is not a number"
    if math.isnan(mass) or mass == draw_in_bin(lo, hi, seed):
        return None
    return (f"its drawn_mass_kg {recorded} is not the mass bin [{lo!r}, {hi!r}) draws from its "
            "seed (rows drawn in other bins?)")


def _inspect_env(sweep: SweepSpec, methods: list[MethodSpec], values: list[float]) -> EnvInfo:
    """Build one env per controller, read its facts and probe the parameter values."""
    envs = {}
    try:
        for spec in methods:
            key = spec.env_key(sweep.env_id)
            if key not in envs:
                envs[key] = make_env(
                    sweep.env_id, spec.controller, sweep.controller_overrides, spec.preset,
                    observation=spec.observation_for(sweep.env_id), robot=spec.robot,
                    robot_overrides=sweep.robot_overrides,
                    impedance_from=spec.impedance_preset(sweep.env_id))
            if spec.carry:
                check_carries(spec, envs[key], sweep.env_id)
        first = next(iter(envs.values()))
        info = describe_env(first, sweep.param)
        check_param(info, sweep.param)
        if sweep.bin_highs:
            check_bin_param(sweep.env_id, info.param_name, task_params(first))
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


def _build_policies(sweep: SweepSpec, methods: list[MethodSpec], env_id: str) -> None:
    """Build each method's policy once (checkpoints load, experts exist), then drop it."""
    for spec in methods:
        env = method_env(sweep.env_id, spec)
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


def _fingerprints(methods: list[MethodSpec], env_id: str) -> dict[str, str | None]:
    """Each method's checkpoint fingerprint (None: it loads none)."""
    out: dict[str, str | None] = {}
    for m in methods:
        path = policy_checkpoint(env_id, m.policy)
        out[m.name] = None if path is None else fingerprint(path)
    return out


def prepare(spec: SweepSpec, options: RunOptions) -> Plan:
    """Check a sweep against its env and output directory without creating any file (the
    checks that need no env were made when ``spec`` and ``options`` were built)."""
    if options.video_episodes:  # an encoder and a GL context, before anything is written
        from impact_eval.video import require_video

        require_video()
    check_env_id(spec.env_id)  # imports the env's module, which may register methods too
    methods = resolve_methods(spec.methods, spec.robot_overrides)
    info = _inspect_env(spec, methods, sorted({*spec.values, *spec.bin_highs}))  # bin edges too
    check_out_dir(options.out)
    continuing = options.resume or options.extend
    previous = runinfo.read_run_json(options.out) if continuing else None
    identity = runinfo.RunIdentity(
        spec=spec, param_name=info.param_name,
        method_controllers={m.name: m.settings_for(spec.env_id) for m in methods},
        policy_fingerprints=_fingerprints(methods, info.env_id))
    if continuing:
        check_same_code(previous, runinfo.git_state(), options.allow_code_change)
        csv_path = options.out / EPISODES_CSV
        has_rows = csv_path.exists() and bool(csvio.read_rows(csv_path))
        runinfo.check_resumable(runinfo.recorded_identity(options.out), identity,
                                extend=options.extend, has_rows=has_rows)
    row_param = bin_param_name(info.param_name) if spec.bin_highs else info.param_name
    done = load_done(spec, options, info, row_param)
    _build_policies(spec, methods, info.env_id)
    config = SweepConfig(spec, options, canonical_env_id=info.env_id,
                         param_name=info.param_name, policy_dt=info.policy_dt)
    return Plan(config=config, env=info, out=options.out, done=done, previous_run=previous,
                identity=identity)
