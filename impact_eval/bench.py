"""``impact-bench``: real-time factor of an IMPACT env with each controller vs raw ``mj_step``.

One run measures, on the same scene and the same scripted-expert trajectory:

1. the full env (1 kHz controller + sensing + physics) with ``controller="impedance"`` and
   ``controller="impact"``;
2. raw ``mj_step`` replaying the exact actuator commands recorded in the IMPACT run, from the
   same initial state (pure physics cost of that trajectory).

It prints real-time factors (simulated seconds per wall second) and the ratios, so the numbers
are comparable across noisy machines. Single process; pin it to one core with ``taskset -c 0``
for a one-core figure.
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import mujoco
import numpy as np

import impact_envs
from impact_envs.policies.protocol import stack_obs
from impact_envs.policies.scripted import make_expert


def _run_env(env_id: str, controller: str, steps: int, seed: int, mass: float):
    env = gym.make(env_id, controller=controller, object_mass=mass).unwrapped
    expert = make_expert(env_id)
    obs, _ = env.reset(seed=seed)
    expert.reset(1)
    sim = env.sim
    start_state = (sim.data.qpos.copy(), sim.data.qvel.copy(), sim.data.ctrl.copy())
    ctrl_log: list[np.ndarray] = []
    plain_step = sim.step

    def recording_step() -> None:
        ctrl_log.append(sim.data.ctrl.copy())
        plain_step()

    sim.step = recording_step
    actions = []
    t0 = time.perf_counter()
    for _ in range(steps):
        action = expert.act(stack_obs([obs]))[0]
        actions.append(action)
        obs, *_ = env.step(action)
    wall = time.perf_counter() - t0
    sim_time = len(ctrl_log) * sim.dt
    return env, sim_time / wall, start_state, np.array(ctrl_log)


def _replay_raw(env, start_state, ctrl_log: np.ndarray) -> float:
    m, d = env.sim.model, env.sim.data
    qpos, qvel, ctrl = start_state
    mujoco.mj_resetData(m, d)
    d.qpos[:], d.qvel[:], d.ctrl[:] = qpos, qvel, ctrl
    mujoco.mj_forward(m, d)
    t0 = time.perf_counter()
    for u in ctrl_log:
        d.ctrl[:] = u
        mujoco.mj_step(m, d)
    return len(ctrl_log) * m.opt.timestep / (time.perf_counter() - t0)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="impact-bench", description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="IMPACT/Hammer-v0", choices=impact_envs.ENV_IDS)
    parser.add_argument("--steps", type=int, default=300, help="policy steps (30 Hz) per run")
    parser.add_argument("--mass", type=float, default=2.5, help="object mass [kg]")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    rtf = {}
    for controller in ("impedance", "impact"):
        env, rtf[controller], start, log = _run_env(
            args.env, controller, args.steps, args.seed, args.mass
        )
    raw = _replay_raw(env, start, log)
    print(
        f"env {args.env}, {args.steps} policy steps ({len(log)} physics ticks), "
        f"mass {args.mass} kg, seed {args.seed}"
    )
    print(f"{'run':<28}{'real-time factor':>18}{'vs raw mj_step':>16}")
    print(f"{'raw mj_step (replay)':<28}{raw:>17.1f}x{1.0:>15.2f}x")
    for controller in ("impedance", "impact"):
        print(
            f"{'env, controller=' + controller:<28}{rtf[controller]:>17.1f}x"
            f"{rtf[controller] / raw:>15.2f}x"
        )
    overhead = 1.0 / rtf["impact"] - 1.0 / raw
    print(
        f"IMPACT controller+sensing overhead per simulated second: {overhead:.3f} s "
        f"({overhead * raw:.2f}x the physics cost)"
    )


if __name__ == "__main__":
    main()
