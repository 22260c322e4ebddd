"""``python -m impact_experiments.trace``: print one episode of a method, every N policy steps.

Usage::

    python -m impact_experiments.trace --env IMPACT/Hammer-v1 --method augmented_dp \
        --value 0.1 --seed 1

Columns: policy step, TCP height, commanded target height, gripper command, object height,
internal-model prediction / slow estimate / raw estimate of the vertical wrench [N], gate
state, the saturated-lift release's scale on the feedforward (``rel_s``, 1 when it does not
act) and the largest robot-table contact force of the step (``hand_n`` [N]). The last line
counts, per joint, the policy steps whose final torque sat at the FR3 limit (87 / 12 Nm).
The traces quoted in docs/results.md come from this command. Calligraphy adds the writing
summary (force in band, stroke RMS) on the last line.
``--robot-set FIELD=VALUE`` changes the robot as in impact-eval (e.g. ``realism=fr3``).
``--full`` runs the episode to its step limit instead of stopping at the first success, and
adds the success test of each printed step (``succ``; HammerBasket judges success at the end).
``--no-joint-friction`` zeroes the arm joints' Coulomb friction in the simulated plant (an
ablation of the robot, not of the controller), to see what the friction dead-band costs.
``--guard`` adds the contact guard's phase (``guard``: open, window, wait, HOLD) and the
applied force feedforward after the guard and its bounds (``ff_x ff_y ff_z`` [N], world
frame), to see what the learned force pushes into a contact. ``--contacts`` adds, under each
printed row, the robot's contacts with the scene and the objects above 5 N (``geom/geom:
normal force [N]``, summed per pair of geoms; the grasp's finger-pad contacts included), to
see what the hand touches.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

import mujoco
import numpy as np

from impact_control.contact_guard import HOLD, OPEN, WAIT, WINDOW
from impact_control.errors import ImpactError
from impact_control.policy import stack_obs
from impact_envs.cli import add_robot_set
from impact_envs.robot.sim_kernels import GROUP_ROBOT
from impact_eval.envs import check_env_id, describe_env, method_env
from impact_eval.methods import resolve_method
from impact_eval.rollout import seed_global_rngs

HEADER = "step  ee_z   tgt_z  grip   obj_z  pred_z  slow_z   ext_z  gate  rel_s  hand_n"
GUARD_HEADER = "  guard   ff_x   ff_y   ff_z"
GUARD_PHASES = {OPEN: "open", WINDOW: "window", WAIT: "wait", HOLD: "HOLD"}
"""``ContactGuard`` phases (``GuardState.phase``) by the guard's own constants."""
CONTACT_MIN_N = 5.0
"""``--contacts`` lists the robot's contacts whose normal force sums above this [N] per pair."""


def robot_contacts(sim) -> str:
    """The robot's contacts with anything not the robot, summed per pair of geoms (robot geom
    first) and above ``CONTACT_MIN_N``, as ``"robot/other: N"`` sorted by force."""
    m, d = sim.model, sim.data
    force, pairs = np.zeros(6), {}
    for i in range(d.ncon):
        g = d.contact.geom[i]
        robot = [int(x) for x in g if sim.geom_group[x] == GROUP_ROBOT]
        if len(robot) != 1:
            continue
        other = int(g[1]) if robot[0] == int(g[0]) else int(g[0])
        mujoco.mj_contactForce(m, d, i, force)
        key = f"{_geom_name(m, robot[0])}/{_geom_name(m, other)}"
        pairs[key] = pairs.get(key, 0.0) + float(force[0])
    shown = sorted(((n, k) for k, n in pairs.items() if n > CONTACT_MIN_N), reverse=True)
    return "; ".join(f"{k}: {n:.0f}" for n, k in shown) or "none"


def _geom_name(model, geom: int) -> str:
    """A geom's name, or its body's where the geom has none."""
    return model.geom(geom).name or model.body(int(model.geom_bodyid[geom])).name


def open_method(env_id: str, method: str, overrides: Sequence[str] = (),
                robot_overrides: Sequence[str] = ()) -> tuple[object, object]:
    """(env, policy) of ``method`` on ``env_id``, as impact-eval builds them (the method's
    controller, preset, robot and observation, e.g. ``impact_authors``' commanded torque
    reading, a camera policy's images)."""
    spec = resolve_method(method)
    env = method_env(check_env_id(env_id), spec, overrides, robot_overrides=robot_overrides)
    return env, spec.build(env_id, env)


def start_episode(env, policy, value: float, seed: int) -> dict:
    """Reset ``env`` at the parameter ``value`` with the episode ``seed`` and the policy for
    one env, its sampling noise from the same seed (as impact-eval); the first observation."""
    seed_global_rngs(seed)  # in the rollout's order: global RNGs, policy, env
    policy.reset(1)
    if hasattr(policy, "seed_envs"):
        policy.seed_envs([seed])
    obs, _ = env.reset(seed=seed, options={describe_env(env).param_name: value})
    return obs


def trace(env_id: str, method: str, value: float, seed: int, every: int,
          overrides: Sequence[str] = (), joint_friction: bool = True,
          robot_overrides: Sequence[str] = (), full: bool = False,
          guard: bool = False, contacts: bool = False) -> list[str]:
    """Run one episode (until success, or with ``full`` the step limit); return the printed
    lines (with ``guard``, the contact guard's columns too; with ``contacts``, a line of the
    robot's contacts under each row)."""
    env, policy = open_method(env_id, method, overrides, robot_overrides)
    limit = np.asarray(env.unwrapped.controller.config.limits.torque_max_nm)
    saturated = np.zeros(len(limit), dtype=int)
    release = env.unwrapped.controller.optional.saturation_release
    if not joint_friction:
        sim = env.unwrapped.sim
        sim.model.dof_frictionloss[sim.arm_dof] = 0.0
    obs = start_episode(env, policy, value, seed)
    task, sim = env.unwrapped.task, env.unwrapped.sim  # the object, also for camera policies
    lines = [HEADER + ("  succ" if full else "") + (GUARD_HEADER if guard else "")]
    step, done = 0, False
    guard_state = env.unwrapped.controller.guard.state
    while not done:
        action = np.asarray(policy.act(stack_obs([obs]))[0])
        obs, _, terminated, truncated, info = env.step(action)
        done = terminated or truncated or (not full and bool(info["is_success"]))
        saturated += np.abs(info["tau_nm"]) >= limit - 0.05
        if step % every == 0 or done:
            lines.append(
                f"{step:4d} {obs['ee_pos'][2]:6.3f} {action[2]:6.3f} {action[9]:5.2f} "
                f"{task.observation(sim)['object_pos'][2]:6.3f} "
                f"{info['wrench_pred_world'][2]:7.1f} "
                f"{info['wrench_slow_world'][2]:7.1f} {info['wrench_ext_world'][2]:7.1f} "
                f"{int(info['gate_open']):5d} {release.scale:6.2f} "
                f"{info['peak_robot_contact_force_n']:7.1f}"
                + (f" {int(info['is_success']):5d}" if full else "")
                + (f" {GUARD_PHASES[float(guard_state.phase[0])]:>6s} "
                   + " ".join(f"{f:6.1f}" for f in guard_state.prev_ff[:3]) if guard else ""))
            if contacts:
                lines.append(f"      contacts: {robot_contacts(sim)}")
        step += 1
    end = (f"success: {bool(info['is_success'])} after {step} steps; steps ending at a joint "
           f"torque limit, joints 1-7: {saturated.tolist()}")
    if "in_band_frac" in info:
        end += (f"; writing: force in band {info['in_band_frac']:.0%}, "
                f"stroke RMS {1e3 * info['stroke_rms_m']:.1f} mm")
    lines.append(end)
    env.close()
    return lines


def main(argv: list[str] | None = None) -> None:
    """Entry point."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="IMPACT/Hammer-v1")
    parser.add_argument("--method", required=True, help="a method name of impact-eval")
    parser.add_argument("--value", type=float, required=True, help="the env's parameter value")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--every", type=int, default=30, help="print every N policy steps")
    parser.add_argument("--controller-set", action="append", default=[],
                        metavar="SECTION.FIELD=VALUE", help="as impact-eval --controller-set")
    parser.add_argument("--no-joint-friction", action="store_true",
                        help="zero the arm joints' Coulomb friction in the simulated plant")
    parser.add_argument("--full", action="store_true",
                        help="run to the step limit, not to the first success")
    parser.add_argument("--guard", action="store_true",
                        help="add the contact guard's phase and the applied force feedforward")
    parser.add_argument("--contacts", action="store_true",
                        help="list the robot's contacts above 5 N under each row")
    add_robot_set(parser)
    args = parser.parse_args(argv)
    if args.every < 1:
        parser.error(f"invalid --every {args.every}; valid: >= 1")
    try:
        lines = trace(args.env, args.method, args.value, args.seed, args.every,
                      args.controller_set, joint_friction=not args.no_joint_friction,
                      robot_overrides=args.robot_set, full=args.full,
                      guard=args.guard, contacts=args.contacts)
    except ImpactError as exc:  # unknown env / method, bad value, missing checkpoint
        print(f"{parser.prog}: error: {' '.join(str(exc).split())}", file=sys.stderr)
        raise SystemExit(2) from None
    print("\n".join(lines))


if __name__ == "__main__":
    main()
