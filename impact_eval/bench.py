"""``impact-bench``: real-time factor of an IMPACT env with each controller vs raw ``mj_step``.

One run measures, on the same scene and the same scripted-expert trajectory:

1. the full env (1 kHz controller + sensing + physics, 30 Hz expert policy) with
   ``controller="impedance"``, ``controller="impact"`` (``default`` preset) and
   ``controller="impact"`` with the ``paper`` preset;
2. raw ``mj_step`` replaying the exact actuator commands recorded in the IMPACT run, from the
   same initial state (pure physics cost of that trajectory).

It prints real-time factors (simulated seconds per wall second) and the ratios, so the numbers
are comparable across noisy machines. Each run is repeated ``--repeat`` times (interleaved) and
the fastest is kept, like ``timeit``; a second column uses the process CPU time, which other
processes on a shared machine disturb less. Single process and thread; pin it to one core with
``taskset -c 0`` for a strict one-core figure. ``--stages`` adds the per-call cost of each
part of a control tick at a state taken from the IMPACT run. ``--pixels`` adds the cost of
pixel observations per policy step and per camera (``bench_pixels.py``), as ratios to the
state-mode env step and to raw ``mj_step``.
"""

from __future__ import annotations

import argparse
import os
import time
import timeit
from dataclasses import dataclass

import gymnasium as gym
import mujoco
import numpy as np

import impact_envs
from impact_control.cli import OneLineParser
from impact_control.errors import ImpactError, InvalidArgumentError
from impact_control.policy import stack_obs
from impact_envs.envs.options import ObservationOptions
from impact_envs.envs.pixels import check_view
from impact_envs.policies.diffusion.config import DiffusionConfig
from impact_envs.policies.experts import make_expert
from impact_eval.bench_episode import episode_costs, print_episode_table
from impact_eval.bench_pixels import pixel_costs, print_pixel_table


@dataclass
class Timing:
    """Best wall and CPU time [s] over repeats of one run."""

    wall_s: float = float("inf")
    cpu_s: float = float("inf")

    def add(self, wall_s: float, cpu_s: float) -> None:
        self.wall_s, self.cpu_s = min(self.wall_s, wall_s), min(self.cpu_s, cpu_s)


RUNS = {"impedance": ("impedance", "default"), "impact": ("impact", "default"),
        "impact_paper": ("impact", "paper")}
"""Row label -> (env ``controller``, ``controller_preset``)."""


def _run_env(env_id: str, run: str, steps: int, seed: int, mass: float):
    """One episode prefix; returns (env, wall s, cpu s, start state, ctrl of every tick)."""
    controller, preset = RUNS[run]
    env = gym.make(env_id, controller=controller, controller_preset=preset,
                   object_mass=mass).unwrapped
    expert = make_expert(env_id)
    obs, _ = env.reset(seed=seed)
    expert.reset(1)
    sim = env.sim
    start_state = (sim.data.qpos.copy(), sim.data.qvel.copy(), sim.data.ctrl.copy())
    ctrl_log = np.zeros((steps * 34, sim.model.nu))
    count = [0]
    plain_step = sim.step

    def recording_step() -> None:
        ctrl_log[count[0]] = sim.data.ctrl
        count[0] += 1
        plain_step()

    sim.step = recording_step
    wall0, cpu0 = time.perf_counter(), time.process_time()
    for _ in range(steps):
        action = expert.act(stack_obs([obs]))[0]
        obs, *_ = env.step(action)
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    sim.step = plain_step
    return env, wall, cpu, start_state, ctrl_log[: count[0]]


def _replay_raw(env, start_state, ctrl_log: np.ndarray) -> tuple[float, float]:
    """(wall s, cpu s) of raw mj_step over ``ctrl_log`` from ``start_state``."""
    m, d = env.sim.model, env.sim.data
    qpos, qvel, ctrl = start_state
    mujoco.mj_resetData(m, d)
    d.qpos[:], d.qvel[:], d.ctrl[:] = qpos, qvel, ctrl
    mujoco.mj_forward(m, d)
    wall0, cpu0 = time.perf_counter(), time.process_time()
    for u in ctrl_log:
        d.ctrl[:] = u
        mujoco.mj_step(m, d)
    return time.perf_counter() - wall0, time.process_time() - cpu0


def _stage_costs(env_id: str, seed: int, mass: float, steps: int) -> dict[str, float]:
    """Per-call CPU cost [us] of each part of a tick, at the state after ``steps`` steps."""
    env = gym.make(env_id, controller="impact", object_mass=mass).unwrapped
    expert = make_expert(env_id)
    obs, _ = env.reset(seed=seed)
    expert.reset(1)
    for _ in range(steps):
        obs, *_ = env.step(expert.act(stack_obs([obs]))[0])
    sim, ctrl, dyn, rng = env.sim, env.controller, env.dynamics, np.random.default_rng(0)
    q, dq, tau = sim.read_sensors(rng)
    pos, quat = env._target_pos, env._target_quat
    ctrl.internal_model.learning_enabled = False  # time inference ticks; SGD is separate
    state = mujoco.MjData(sim.model)
    mujoco.mj_copyData(state, sim.model, sim.data)

    def step() -> None:
        mujoco.mj_copyData(sim.data, sim.model, state)
        mujoco.mj_step(sim.model, sim.data)

    def time_us(fn, number: int = 2000) -> float:
        runs = timeit.repeat(fn, number=number, repeat=5, timer=time.process_time)
        return min(runs) / number * 1e6

    costs = {
        "read_sensors": time_us(lambda: sim.read_sensors(rng)),
        "gripper_width": time_us(sim.gripper_width),
        "dynamics.update": time_us(lambda: dyn.update(q, dq)),
        "compute (incl. update)": time_us(lambda: ctrl.compute(q, dq, tau, pos, quat)),
        "apply": time_us(lambda: sim.apply(sim.tau_applied, -1.0)),
        "contact_forces": time_us(sim.contact_forces),
    }
    copy_only = time_us(lambda: mujoco.mj_copyData(sim.data, sim.model, state), 500)
    costs["mj_step"] = time_us(step, 500) - copy_only
    model = ctrl.internal_model
    x, target, mask = model.history_input().copy(), np.zeros(6, np.float32), np.ones(6, np.float32)
    costs["SGD step (every 5th tick while learning)"] = time_us(
        lambda: model.train_step(x, target, mask), 50
    )
    return costs


def _print_table(args: argparse.Namespace, rtf: dict[str, Timing], n_ticks: int) -> None:
    sim_s = n_ticks * 0.001
    raw = rtf["raw"]
    print(
        f"env {args.env}, {args.steps} policy steps ({n_ticks} physics ticks), "
        f"mass {args.mass} kg, seed {args.seed}, best of {args.repeat} runs each"
    )
    load = ", ".join(f"{v:.2f}" for v in os.getloadavg())
    print(f"machine: {os.cpu_count()} CPUs, load average {load} (1, 5, 15 min)")
    header = f"{'run':<28}{'real-time factor':>18}{'vs raw mj_step':>16}"
    print(f"{header}{'CPU-time RTF':>15}{'vs raw':>9}")
    rows = [("raw mj_step (replay)", raw)] + [
        (f"env, {c}", rtf[c]) for c in RUNS
    ]
    for name, t in rows:
        print(
            f"{name:<28}{sim_s / t.wall_s:>17.1f}x{raw.wall_s / t.wall_s:>15.2f}x"
            f"{sim_s / t.cpu_s:>14.1f}x{raw.cpu_s / t.cpu_s:>8.2f}x"
        )
    wall_over = (rtf["impact"].wall_s - raw.wall_s) / sim_s
    cpu_over = (rtf["impact"].cpu_s - raw.cpu_s) / sim_s
    print(
        f"IMPACT controller+sensing overhead per simulated second: {wall_over:.3f} s "
        f"({wall_over * sim_s / raw.wall_s:.2f}x the physics cost); CPU time {cpu_over:.3f} s "
        f"({cpu_over * sim_s / raw.cpu_s:.2f}x)"
    )


def _check_args(args: argparse.Namespace) -> None:
    """One-line ``InvalidArgumentError`` for a step count, repeat count, mass or image size
    out of range."""
    if args.steps < 2 or args.repeat < 1:
        raise InvalidArgumentError(
            f"need --steps >= 2 and --repeat >= 1, got {args.steps} and {args.repeat}")
    if args.image_size < 1:
        raise InvalidArgumentError(f"need --image-size >= 1, got {args.image_size}")
    env = gym.make(args.env)
    try:
        env.unwrapped.task.mass_param().validate(args.mass)  # every bench env declares one
        size = args.image_size
        cameras = episode_cameras(args)
        check_view(env.unwrapped.sim.model, "--image-size", cameras, size, size)
        if args.episode:  # the DP's shape: horizon and executed steps, as its config checks
            DiffusionConfig(horizon=args.horizon, n_action_steps=args.action_steps)
    finally:
        env.close()


def episode_cameras(args: argparse.Namespace) -> tuple[str, ...]:
    """``--cameras`` of ``--episode`` (the pixel default when not given; none otherwise)."""
    if not args.episode:
        return ()
    return (tuple(c.strip() for c in args.cameras.split(",")) if args.cameras
            else ObservationOptions().cameras)


def main(argv: list[str] | None = None) -> None:
    parser = OneLineParser(prog="impact-bench", description=__doc__.splitlines()[0])
    parser.add_argument("--env", default=impact_envs.ENV_IDS[0],
                        choices=impact_envs.REGISTERED_IDS)
    parser.add_argument("--steps", type=int, default=300, help="policy steps (30 Hz) per run")
    parser.add_argument("--mass", type=float, default=2.5, help="object mass [kg]")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--repeat", type=int, default=3, help="runs of each kind; best kept")
    parser.add_argument("--stages", action="store_true", help="also print per-stage costs")
    parser.add_argument("--pixels", action="store_true",
                        help="also print the pixel-observation cost per step and camera")
    parser.add_argument("--image-size", type=int, default=ObservationOptions().image_width,
                        help="--pixels / --episode image width and height [px]")
    parser.add_argument("--episode", action="store_true",
                        help="also print a camera policy's episode cost: physics, controller, "
                             "rendering, policy (bench_episode.py)")
    parser.add_argument("--cameras", default=None,
                        help="--episode cameras, comma list (default: the env's pixel default)")
    parser.add_argument("--horizon", type=int, default=16, help="--episode: DP horizon")
    parser.add_argument("--action-steps", type=int, default=8,
                        help="--episode: DP actions executed per replan")
    args = parser.parse_args(argv)
    try:
        _check_args(args)
    except ImpactError as exc:
        parser.exit(2, f"impact-bench: error: {exc}\n")
    rtf = {k: Timing() for k in (*RUNS, "raw")}
    for _ in range(max(1, args.repeat)):
        replay = None
        for run in RUNS:
            env, wall, cpu, start, log = _run_env(args.env, run, args.steps, args.seed, args.mass)
            rtf[run].add(wall, cpu)
            if run == "impact":
                replay = (env, start, log)
        rtf["raw"].add(*_replay_raw(*replay))
    _print_table(args, rtf, len(replay[2]))
    if args.stages:
        print(f"per-call CPU cost [us] at step {args.steps // 2} of the IMPACT run (best of 5):")
        for name, us in _stage_costs(args.env, args.seed, args.mass, args.steps // 2).items():
            print(f"  {name:<42}{us:8.1f}")
    if args.pixels:
        raw_step = np.array([rtf["raw"].wall_s, rtf["raw"].cpu_s]) / args.steps
        costs = pixel_costs(args.env, args.steps, args.seed, args.mass, args.image_size,
                            args.repeat)
        print_pixel_table(costs, raw_step, args.image_size)
    if args.episode:
        cameras = episode_cameras(args)
        costs = episode_costs(args.env, cameras, args.image_size, args.steps, args.seed,
                              args.mass, args.repeat, (args.horizon, args.action_steps),
                              rtf["raw"].wall_s / args.steps)
        steps = gym.spec(args.env).max_episode_steps or args.steps
        print_episode_table(costs, steps, args.image_size, cameras)


if __name__ == "__main__":
    main()
