"""``python -m impact_experiments.contact_wedge``: what the object's contacts hold at one
step of an episode: each contact's normal and friction force, and their net (issue 54,
"HammerBasket's contact figures").

The contact columns of ``episodes.csv`` (``safety.scene_contact``) sum the contacts' *normal*
forces. A body wedged between two surfaces with high friction (the hammer's μ = 4 against the
basket) can hold normal forces far above any force applied to it, cancelled by its friction
forces: the sum of normals then reads kilonewtons while the net force the environment exerts
on it is its weight. This prints both, so the two cases can be told apart.

    python -m impact_experiments.contact_wedge --env IMPACT/HammerBasket-v1 \\
        --method augmented_dp --value 8.584887852260612 --seed 1180178287 --steps 220
"""

from __future__ import annotations

import mujoco
import numpy as np

from impact_control.cli import OneLineParser
from impact_control.errors import ImpactError
from impact_control.policy import stack_obs
from impact_envs.robot.sim import contact_force_world
from impact_experiments.trace import open_method, start_episode


def contact_lines(model: mujoco.MjModel, data: mujoco.MjData, body: str) -> list[str]:
    """One line per contact of ``body`` (geoms, normal force [N], normal, penetration [mm],
    friction [N]) and a last line with the net force of the environment on it [N, world],
    from the normals alone and with friction, beside its weight."""
    target, f6 = model.body(body).id, np.zeros(6)
    net, net_normal, lines = np.zeros(3), np.zeros(3), []
    for i in range(data.ncon):
        c = data.contact[i]
        bodies = model.geom_bodyid[c.geom[0]], model.geom_bodyid[c.geom[1]]
        if target not in bodies:
            continue
        mujoco.mj_contactForce(model, data, i, f6)
        frame = c.frame.reshape(3, 3)
        sign = 1.0 if bodies[1] == target else -1.0  # MuJoCo's normal: geom 1 -> geom 2
        net += sign * contact_force_world(model, data, i)
        net_normal += sign * f6[0] * frame[0]
        lines.append(f"{model.geom(c.geom[0]).name}-{model.geom(c.geom[1]).name}: normal "
                     f"{f6[0]:.0f} N along {np.round(frame[0], 3).tolist()}, penetration "
                     f"{-1000 * c.dist:.2f} mm, friction {np.round(f6[1:3], 0).tolist()} N")
    weight = model.body_subtreemass[target] * -model.opt.gravity[2]
    lines.append(f"net force on {body}: normals only {np.round(net_normal, 1).tolist()} N, "
                 f"with friction {np.round(net, 1).tolist()} N; its weight {weight:.1f} N")
    return lines


def main(argv: list[str] | None = None) -> None:
    """Entry point."""
    p = OneLineParser(description=__doc__.splitlines()[0])
    p.add_argument("--env", default="IMPACT/HammerBasket-v1")
    p.add_argument("--method", required=True)
    p.add_argument("--value", type=float, required=True, help="the env's parameter value")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--steps", type=int, required=True, help="policy steps before the reading")
    p.add_argument("--body", default="hammer", help="the body whose contacts are read")
    args = p.parse_args(argv)
    if args.steps < 0:
        p.fail(f"invalid --steps {args.steps}; valid: >= 0")
    try:
        env, policy = open_method(args.env, args.method)
        sim = env.unwrapped.sim
        bodies = [sim.model.body(i).name for i in range(sim.model.nbody)]
        if args.body not in bodies:
            p.fail(f"invalid --body {args.body!r}; valid choices: {', '.join(bodies[1:])}")
        obs = start_episode(env, policy, args.value, args.seed)
        for _ in range(args.steps):
            obs, *_ = env.step(np.asarray(policy.act(stack_obs([obs]))[0]))
    except ImpactError as exc:
        p.fail(" ".join(str(exc).split()))
    print("\n".join(contact_lines(sim.model, sim.data, args.body)))
    robot, _ = sim.contact_forces()
    print(f"robot-environment normal force: {robot:.1f} N; gripper opening "
          f"{sim.gripper_width() * 1000:.0f} mm")


if __name__ == "__main__":
    main()
