"""Run a policy of the ``Policy`` protocol on an FR3 (or a libfranka-protocol simulator).

    python examples/robot_policy.py --host 127.0.0.1 --seconds 12

The demo policy moves the TCP on a 3 cm circle (impact_franka/demo.py). For a trained policy,
build it in ``make_policy`` (e.g. ``functools.partial`` of a checkpoint loader) and return
what the robot cannot measure from ``extra_obs`` (an object's pose from your tracker, named as
the env's observation names it). Keep a hand on the emergency stop (docs/hardware.md).
"""

from __future__ import annotations

import argparse
import functools

import numpy as np
import pylibfranka as plf

from impact_control.controller import ImpactController
from impact_control.dynamics import PinocchioArm
from impact_franka.demo import CirclePolicy
from impact_franka.fci import fr3_config
from impact_franka.policy_loop import PolicyTarget
from impact_franka.runner import run_loop


def no_extra_obs() -> dict[str, np.ndarray]:
    """What the robot cannot measure, named as the env's observation names it; for the Hammer
    task e.g. {"object_pos": ..., "object_rot6d": ..., "goal_pos": ...} from your tracker."""
    return {}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host", required=True)
    parser.add_argument("--seconds", type=float, default=12.0)
    args = parser.parse_args()
    robot = plf.Robot(args.host, plf.RealtimeConfig.kIgnore)
    controller = ImpactController(PinocchioArm(), fr3_config(), mode="impact")
    source = PolicyTarget(functools.partial(CirclePolicy, 0.03, 4.0), no_extra_obs,
                          workspace=(np.array([0.2, -0.4, 0.1]), np.array([0.8, 0.4, 0.8])))
    report = run_loop(robot, controller, args.seconds, source)
    print(f"{report.ticks} ticks at {report.rate_hz:.0f} Hz, {source.actions} actions "
          f"({source.refused} refused), largest tracking error "
          f"{1e3 * report.pos_error_max_m:.2f} mm, robot errors: "
          f"{report.robot_errors or 'none'}")


if __name__ == "__main__":
    main()
