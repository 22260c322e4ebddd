"""``impact-collect``: record successful scripted-expert demonstrations into a zarr store.

Usage::

    impact-collect --env IMPACT/Hammer-v1 --out data/hammer_vanilla.zarr --episodes 200 --mass 0.2
    impact-collect --env IMPACT/Hammer-v1 --out data/hammer_aug.zarr --episodes 200 \\
        --mass-range 0.1:8
    impact-collect --env IMPACT/Dumbbell-v1 --out data/db_aug.zarr --episodes 200 \\
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
from collections.abc import Callable
from pathlib import Path

import gymnasium as gym
from tqdm import tqdm

import impact_envs
from impact_control.cli import OneLineParser
from impact_control.errors import ImpactError
from impact_learn.collect_config import CollectConfig, parse_param_spec
from impact_learn.collect_pixels import (
    add_observation_arguments,
    observation_attrs,
    observation_from_args,
    stored_dims,
    with_cameras,
)
from impact_learn.collect_run import (
    AttemptBatch,
    CollectionError,
    EpisodeResult,
    Expert,
    attempt_batches,
    local_batch_results,
)
from impact_learn.collect_store import open_writer, partial_path
from impact_learn.dataset import EpisodeMeta, ReplayWriter


def default_env_factory(cfg: CollectConfig) -> Callable[[], gym.Env]:
    """Factory of ``gym.make(env_id, controller=..., controller_preset=...)`` with the fixed
    parameter value.

    The value goes to the env's own swept parameter (``env.param_name``): the ``object_mass``
    kwarg for Hammer and Dumbbell (and envs without ``param_name``), ``task_params`` for the
    others (Calligraphy: ``tool_mass``).
    """

    def make() -> gym.Env:
        kwargs: dict[str, object] = {"controller": cfg.controller}
        if cfg.controller_preset != "default":  # an env without presets still takes default
            kwargs["controller_preset"] = cfg.controller_preset
        env = gym.make(cfg.env_id, **kwargs)
        if cfg.param is None:
            return env
        name = getattr(env.unwrapped, "param_name", "object_mass")
        env.close()
        value = ({"object_mass": cfg.param} if name == "object_mass"
                 else {"task_params": {name: cfg.param}})
        return gym.make(cfg.env_id, **kwargs, **value)

    return make


def default_expert_factory(cfg: CollectConfig) -> Callable[[], Expert]:
    """Factory of the scripted expert of ``cfg.env_id``."""

    def make() -> Expert:
        from impact_envs.policies.experts import make_expert

        return make_expert(cfg.env_id, compensation=cfg.compensation, expert=cfg.expert)

    return make


def store_attrs(cfg: CollectConfig, param_name: str) -> dict:
    """Store attributes that a resumed run must match."""
    attrs = {
        "env_id": cfg.env_id,
        "param_name": param_name,
        "param_spec": cfg.param_spec(),
        "controller": cfg.controller,
        "controller_preset": cfg.controller_preset,
        "expert": {"name": cfg.expert, "compensation": cfg.compensation},
        "seed": cfg.seed,
        "post_success_steps": cfg.post_success_steps,
        "package_version": impact_envs.__version__,
    }
    if cfg.observation.uses_images:  # a state store's attributes are as before
        attrs["observation"] = observation_attrs(cfg.observation)
    return attrs


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

    ``env_factory``/``expert_factory`` default to ``gym.make`` and ``make_expert`` (with
    ``executor="ray"`` they travel to the workers, so they must pickle with cloudpickle).
    Batches of ``n_envs`` attempts run here one after another, or as Ray tasks several at a
    time; either way their episodes are stored in attempt order, so the store is the same.
    """
    make_env = with_cameras(env_factory or default_env_factory(cfg), cfg.observation)
    make_expert = expert_factory or default_expert_factory(cfg)
    envs = [make_env()]
    expert = make_expert()  # before the store exists: an expert that cannot be built is bad input
    param_name = getattr(envs[0].unwrapped, "param_name", "object_mass")
    _check_param_values(envs[0], param_name, cfg)
    writer = open_writer(cfg, stored_dims(envs[0]), store_attrs(cfg, param_name))
    attempts = writer.attempts()
    attempt = max(int(writer.root.attrs.get("n_attempts", 0)), int(attempts.max(initial=-1)) + 1)
    batches = attempt_batches(cfg, attempt, param_name)
    if cfg.executor == "ray":
        from impact_learn.collect_ray import ray_batch_results

        results = ray_batch_results(cfg, make_env, make_expert, batches)
    else:
        envs += [make_env() for _ in range(cfg.n_envs - 1)]
        results = local_batch_results(envs, expert, batches, cfg.post_success_steps)
    bar = tqdm(total=cfg.episodes, initial=writer.n_episodes, disable=not cfg.progress)
    try:
        while writer.n_episodes < cfg.episodes:
            item = next(results, None)
            if item is None:
                break  # attempt limit reached
            attempt = _store_batch(writer, cfg.episodes, *item, bar)
            writer.set_attrs(n_attempts=attempt)
            bar.set_postfix(attempts=attempt, success=f"{writer.n_episodes / attempt:.2f}")
    finally:
        results.close()
        bar.close()
        for env in envs:
            env.close()
    stored = writer.n_episodes
    if stored >= cfg.episodes:
        os.replace(writer.path, cfg.out)  # the store appears under --out only when complete
    return stored


def _store_batch(writer: ReplayWriter, target: int, batch: AttemptBatch,
                 results: list[EpisodeResult], bar: tqdm) -> int:
    """Append the batch's successes in attempt order until ``target`` demos are stored;
    returns the next attempt index (after the last attempt that counted)."""
    attempt = batch.ids[0]
    for k, seed, result in zip(batch.ids, batch.spec.seeds, results, strict=True):
        if writer.n_episodes >= target:
            break  # later attempts of this batch do not count (resume redoes them)
        if result.success:
            writer.append_episode(result.obs, result.actions,
                                  EpisodeMeta(result.param, seed, True, k))
            bar.update(1)
        attempt = k + 1
    return attempt


def build_parser() -> argparse.ArgumentParser:
    """Command-line interface of ``impact-collect``."""
    parser = OneLineParser(prog="impact-collect", description=__doc__.splitlines()[0])
    parser.add_argument("--env", required=True, help="env id, e.g. IMPACT/Hammer-v2")
    parser.add_argument("--out", required=True, help="output store (*.zarr)")
    parser.add_argument("--episodes", type=int, default=200, help="successful demos to keep")
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--mass", type=float, help="fixed parameter value (mass [kg])")
    group.add_argument("--mass-range", help="uniform range LO:HI")
    group.add_argument("--mass-list", help="comma-separated values, cycled over attempts")
    parser.add_argument(
        "--compensation", default="none",
        help="how the expert meets a load's sag: none | closed_loop | privileged (ablation)")
    parser.add_argument(
        "--expert", default="scripted",
        help="scripted (the task's expert) | authors (HammerBasket: the paper authors' "
             "demonstrator, re-based targets; with --compensation privileged their offset)")
    parser.add_argument("--controller", default="impedance", help="impedance | impact")
    parser.add_argument("--controller-preset", default="default",
                        help="the controller's named configuration, e.g. authors_sim (with "
                             "--controller impedance: the authors' baselines' controller)")
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
    parser.add_argument("--executor", default="local",
                        help="local (this process) | ray (batches as Ray tasks: docs/scale.md)")
    parser.add_argument("--ray-address", metavar="ADDR",
                        help="Ray cluster to join (default: $RAY_ADDRESS or a new local one)")
    add_observation_arguments(parser)
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
                       f"{', '.join(impact_envs.REGISTERED_IDS)}\n")
    except ImpactError as exc:
        code = 1 if isinstance(exc, CollectionError) else 2  # a failed run, not bad input
        parser.exit(code, f"impact-collect: error: {exc}\n")
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
        expert=args.expert,
        controller=args.controller,
        controller_preset=args.controller_preset,
        seed=args.seed,
        post_success_steps=args.post_success_steps,
        n_envs=args.n_envs,
        max_attempts=args.max_attempts,
        resume=args.resume,
        progress=not args.no_progress,
        executor=args.executor,
        ray_address=args.ray_address,
        observation=observation_from_args(args),
    )


if __name__ == "__main__":
    main()
