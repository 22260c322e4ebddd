"""``impact-collect``: record successful scripted-expert demonstrations into a zarr store.

Usage::

    impact-collect --env IMPACT/Hammer-v0 --out data/hammer_vanilla.zarr --episodes 200 --mass 0.2
    impact-collect --env IMPACT/Hammer-v0 --out data/hammer_aug.zarr --episodes 200 \\
        --mass-range 0.1:8
    impact-collect --env IMPACT/Dumbbell-v0 --out data/db_aug.zarr --episodes 200 \\
        --mass-list 2.5,5 --resume

Attempt ``k`` uses env seed ``SeedSequence([seed, k])`` and a parameter drawn from
``SeedSequence([seed, k, 1])`` (``--mass-range``), ``values[k % len]`` (``--mass-list``) or the
fixed ``--mass``. Attempts run ``--n-envs`` at a time in lockstep; the successful episodes of
each batch are appended in attempt order, so ``--resume`` reproduces an uninterrupted run.
Demos are written to ``OUT.partial``, which is renamed to ``OUT`` once every requested demo is
stored: ``OUT`` is always a complete store.
"""

from __future__ import annotations

import argparse
import os
import shutil
from collections.abc import Callable
from pathlib import Path

import gymnasium as gym
import numpy as np
import zarr
from tqdm import tqdm

import impact_envs
from impact_envs.cli import OneLineParser
from impact_envs.errors import ImpactError, InvalidArgumentError
from impact_learn.collect_config import CollectConfig, parse_param_spec
from impact_learn.collect_run import AttemptSpec, Expert, run_attempts
from impact_learn.dataset import EpisodeMeta, ReplayWriter


def attempt_seed(base_seed: int, attempt: int) -> int:
    """Env reset seed of attempt ``attempt``."""
    return int(np.random.SeedSequence([base_seed, attempt]).generate_state(1)[0])


def attempt_param(cfg: CollectConfig, attempt: int) -> float | None:
    """Randomized parameter of attempt ``attempt`` (None: the env's default)."""
    if cfg.param_range is not None:
        rng = np.random.default_rng(np.random.SeedSequence([cfg.seed, attempt, 1]))
        return float(rng.uniform(*cfg.param_range))
    if cfg.param_list is not None:
        return float(cfg.param_list[attempt % len(cfg.param_list)])
    return cfg.param


def default_env_factory(cfg: CollectConfig) -> Callable[[], gym.Env]:
    """Factory of ``gym.make(env_id, controller=...)`` with the fixed parameter value.

    The value goes to the env's own swept parameter (``env.param_name``): the ``object_mass``
    kwarg for Hammer and Dumbbell (and envs without ``param_name``), ``task_params`` for the
    others (Calligraphy: ``tool_mass``).
    """

    def make() -> gym.Env:
        env = gym.make(cfg.env_id, controller=cfg.controller)
        if cfg.param is None:
            return env
        name = getattr(env.unwrapped, "param_name", "object_mass")
        env.close()
        value = ({"object_mass": cfg.param} if name == "object_mass"
                 else {"task_params": {name: cfg.param}})
        return gym.make(cfg.env_id, controller=cfg.controller, **value)

    return make


def default_expert_factory(cfg: CollectConfig) -> Callable[[], Expert]:
    """Factory of the scripted expert of ``cfg.env_id``."""

    def make() -> Expert:
        from impact_envs.policies.experts import make_expert

        return make_expert(cfg.env_id, compensation=cfg.compensation)

    return make


def store_attrs(cfg: CollectConfig, param_name: str) -> dict:
    """Store attributes that a resumed run must match."""
    return {
        "env_id": cfg.env_id,
        "param_name": param_name,
        "param_spec": cfg.param_spec(),
        "controller": cfg.controller,
        "controller_preset": "default",  # gym.make's default; the demos' IMPACT settings
        "expert": {"name": "scripted", "compensation": cfg.compensation},
        "seed": cfg.seed,
        "post_success_steps": cfg.post_success_steps,
        "package_version": impact_envs.__version__,
    }


def _check_param_values(env: gym.Env, param_name: str, cfg: CollectConfig) -> None:
    """Every value the run can draw must be in the env's range (checked before the store
    exists, so a bad range leaves nothing behind). Envs without task parameters are skipped."""
    task = getattr(env.unwrapped, "task", None)
    if task is None or not hasattr(task, "param"):
        return
    spec = cfg.param_spec()
    for value in spec.get("values", []):
        task.param(param_name).validate(value)


def collect(
    cfg: CollectConfig,
    *,
    env_factory: Callable[[], gym.Env] | None = None,
    expert_factory: Callable[[], Expert] | None = None,
) -> int:
    """Collect until ``cfg.episodes`` successful demos are stored; returns the number stored.

    ``env_factory``/``expert_factory`` default to ``gym.make`` and ``make_expert``.
    """
    make_env = env_factory or default_env_factory(cfg)
    envs = [make_env() for _ in range(cfg.n_envs)]
    expert = (expert_factory or default_expert_factory(cfg))()
    param_name = getattr(envs[0].unwrapped, "param_name", "object_mass")
    _check_param_values(envs[0], param_name, cfg)
    space = envs[0].observation_space
    obs_dims = {k: int(np.prod(s.shape)) for k, s in space.spaces.items()}
    writer = _open_store(cfg, obs_dims, store_attrs(cfg, param_name))
    attempts = writer.attempts()
    attempt = max(int(writer.root.attrs.get("n_attempts", 0)), int(attempts.max(initial=-1)) + 1)
    bar = tqdm(total=cfg.episodes, initial=writer.n_episodes, disable=not cfg.progress)
    try:
        while writer.n_episodes < cfg.episodes and attempt < cfg.attempt_limit:
            ids = list(range(attempt, min(attempt + cfg.n_envs, cfg.attempt_limit)))
            seeds = [attempt_seed(cfg.seed, k) for k in ids]
            params = [attempt_param(cfg, k) for k in ids]
            spec = AttemptSpec(seeds, params, param_name)
            results = run_attempts(envs[: len(ids)], expert, spec, cfg.post_success_steps)
            for k, seed, result in zip(ids, seeds, results, strict=True):
                if writer.n_episodes >= cfg.episodes:
                    break  # later attempts of this batch do not count (resume redoes them)
                if result.success:
                    meta = EpisodeMeta(result.param, seed, True, k)
                    writer.append_episode(result.obs, result.actions, meta)
                    bar.update(1)
                attempt = k + 1
            writer.set_attrs(n_attempts=attempt)
            bar.set_postfix(attempts=attempt, success=f"{writer.n_episodes / attempt:.2f}")
    finally:
        bar.close()
        for env in envs:
            env.close()
    stored = writer.n_episodes
    if stored >= cfg.episodes:
        os.replace(writer.path, cfg.out)  # the store appears under --out only when complete
    return stored


def partial_path(out: str | Path) -> Path:
    """Where a collection writes until it is complete: ``OUT.partial``."""
    return Path(f"{out}.partial")


def _stored_episodes(path: Path) -> int:
    """Complete episodes in a store (0 when it cannot be read, e.g. torn at creation)."""
    try:
        return int(zarr.open_group(str(path), mode="r")["meta/episode_ends"].shape[0])
    except (KeyError, OSError, ValueError, zarr.errors.BaseZarrError):
        return 0


def _open_store(cfg: CollectConfig, obs_dims: dict[str, int], attrs: dict) -> ReplayWriter:
    """The writer on ``OUT.partial`` (renamed to ``OUT`` when complete).

    A partial store without a complete episode (a run that failed early) is replaced; one
    holding episodes is continued by ``--resume`` and otherwise refused. ``--resume`` on a
    finished ``OUT`` checks its attributes, then moves it back to ``OUT.partial`` to append.
    """
    final, work = Path(cfg.out), partial_path(cfg.out)
    if work.exists() and not cfg.resume:
        n = _stored_episodes(work)
        if n:
            raise InvalidArgumentError(
                f"{work} holds {n} episodes of an unfinished run; pass --resume to continue it "
                "or delete it")
        shutil.rmtree(work)
    if final.exists():
        if not cfg.resume:
            raise InvalidArgumentError(f"{final} exists; pass --resume to append or remove it")
        if work.exists():
            raise InvalidArgumentError(f"both {final} and {work} exist; delete one of them")
        ReplayWriter(final, obs_dims, attrs, append=True)  # refuses other attributes here
        os.replace(final, work)
    return ReplayWriter(work, obs_dims, attrs, append=cfg.resume)


def build_parser() -> argparse.ArgumentParser:
    """Command-line interface of ``impact-collect``."""
    parser = OneLineParser(prog="impact-collect", description=__doc__.splitlines()[0])
    parser.add_argument("--env", required=True, help="env id, e.g. IMPACT/Hammer-v0")
    parser.add_argument("--out", required=True, help="output store (*.zarr)")
    parser.add_argument("--episodes", type=int, default=200, help="successful demos to keep")
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--mass", type=float, help="fixed parameter value (mass [kg])")
    group.add_argument("--mass-range", help="uniform range LO:HI")
    group.add_argument("--mass-list", help="comma-separated values, cycled over attempts")
    parser.add_argument(
        "--compensation", default="none",
        help="how the expert meets a load's sag: none | closed_loop | privileged (ablation)")
    parser.add_argument("--controller", default="impedance", help="impedance | impact")
    parser.add_argument("--seed", type=int, default=0, help="base seed")
    parser.add_argument(
        "--post-success-steps",
        type=int,
        default=15,
        help="steps recorded after the first success (0: stop at success)",
    )
    parser.add_argument("--n-envs", type=int, default=8, help="envs stepped in lockstep")
    parser.add_argument("--max-attempts", type=int, help="default: 3 x episodes + n-envs")
    parser.add_argument("--resume", action="store_true", help="append to an existing store")
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    return parser


def main(argv: list[str] | None = None) -> None:
    """Entry point of ``impact-collect``; bad input exits 2 with a one-line message."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        cfg = config_from_args(args)
        stored = collect(cfg)
    except gym.error.Error:
        parser.exit(2, f"impact-collect: error: unknown env {args.env!r}; valid: "
                       f"{', '.join(impact_envs.ENV_IDS)}\n")
    except ImpactError as exc:
        parser.exit(2, f"impact-collect: error: {exc}\n")
    if stored < cfg.episodes:
        raise SystemExit(
            f"only {stored}/{cfg.episodes} successful demos after {cfg.attempt_limit} attempts; "
            f"kept in {partial_path(cfg.out)} (--resume with a larger --max-attempts continues)"
        )
    print(f"{stored} demos in {cfg.out}")


def config_from_args(args: argparse.Namespace) -> CollectConfig:
    """``CollectConfig`` of parsed ``impact-collect`` arguments (validated)."""
    param, param_range, param_list = parse_param_spec(args.mass, args.mass_range, args.mass_list)
    return CollectConfig(
        env_id=args.env,
        out=str(Path(args.out)),
        episodes=args.episodes,
        param=param,
        param_range=param_range,
        param_list=param_list,
        compensation=args.compensation,
        controller=args.controller,
        seed=args.seed,
        post_success_steps=args.post_success_steps,
        n_envs=args.n_envs,
        max_attempts=args.max_attempts,
        resume=args.resume,
        progress=not args.no_progress,
    )


if __name__ == "__main__":
    main()
