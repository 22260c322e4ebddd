"""``impact-robot``: IMPACT on an FR3 (or a libfranka-protocol simulator) through pylibfranka.

    impact-robot check --host HOST [--seconds S]
        connect, print the robot mode and errors, our model against Franka's at the current
        configuration, our TCP against the robot's O_T_EE, and the loop timing over S seconds
        of zero torques (the robot's gravity compensation alone)
    impact-robot hold --host HOST [--controller impact|impedance] [--preset default|paper]
                      [--model pinocchio|franka] [--max-payload-kg KG] [--seconds S] [--out DIR]
        hold the current TCP pose with the FR3 configuration (fci.fr3_config); DIR gets
        ticks.csv (one row per control tick), run.json and protocol.png/.pdf
    impact-robot teach --host HOST --poses FILE --name NAME [--float-seconds S]
        float the arm for S seconds (zero torques: guide it by hand), then record its TCP
        pose under NAME in FILE
    impact-robot pick-place --host HOST --pick NAME|X,Y,Z --place NAME|X,Y,Z [--poses FILE]
                      [--gripper-host HOST] [--grasp-width-m W] [--controller ...] [--out DIR]
        the paper's dumbbell task: open, pick the object at --pick, carry it to --place,
        release, retreat (pick_place.py), the Franka Hand through pylibfranka's Gripper

Every command sets the collision thresholds for ``--max-payload-kg`` (collision.py) and
refuses to start while the robot reports errors unless ``--recover`` (libfranka's automatic
error recovery). Exit 0 after a clean finish; 1 with one line naming the robot's errors (or
the failed step) otherwise; 2 on bad arguments. A real robot needs a real-time kernel
(``--realtime enforce``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from impact_envs.cli import OneLineParser
from impact_envs.control.controller import CONTROLLERS
from impact_envs.control.presets import PRESETS
from impact_envs.errors import ImpactError
from impact_franka import session
from impact_franka.fci import TORQUE_SOURCES
from impact_franka.runner import BUDGET_S

REALTIME = ("ignore", "enforce")
MODELS = ("pinocchio", "franka")
COMMANDS = ("check", "hold", "teach", "pick-place")


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="impact-robot", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    for name in COMMANDS:
        p = sub.add_parser(name)
        p.add_argument("--host", required=True, help="robot (FCI) address, e.g. 172.16.0.2")
        p.add_argument("--seconds", type=float, default=60.0 if name == "pick-place" else 2.0,
                       help="length of the run (pick-place: the longest it may take)")
        p.add_argument("--realtime", choices=REALTIME, default="ignore",
                       help="libfranka RealtimeConfig (enforce: needs a real-time kernel)")
        p.add_argument("--max-payload-kg", type=float, default=0.0,
                       help="largest load handed over without set_load; raises the collision "
                       "thresholds by 1.5x what it reads (docs/franka.md)")
        p.add_argument("--torque-source", choices=TORQUE_SOURCES, default="tau_J",
                       help="measured joint torque: tau_J (an FR3) or tau_J+g (a simulator "
                       "whose tau_J leaves gravity out, e.g. franka-sim)")
        p.add_argument("--recover", action="store_true",
                       help="call automatic_error_recovery if the robot reports errors")
        if name in ("hold", "pick-place"):
            _add_run_arguments(p)
        if name == "hold":
            p.add_argument("--step-m", type=_vector3, default=None, metavar="DX,DY,DZ",
                           help="move the held target by this offset [m, base frame] once")
            p.add_argument("--step-at-s", type=float, default=1.0,
                           help="when the step happens [s into the hold]")
        if name == "teach":
            p.add_argument("--poses", type=Path, required=True, help="taught poses (JSON)")
            p.add_argument("--name", required=True, help="name of the pose to record")
            p.add_argument("--float-seconds", type=float, default=0.0,
                           help="float the arm (zero torques) this long before recording")
        if name == "pick-place":
            _add_pick_place_arguments(p)
    return parser


def _add_run_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--controller", choices=CONTROLLERS, default="impact")
    p.add_argument("--preset", choices=PRESETS, default="default")
    p.add_argument("--model", choices=MODELS, default="pinocchio",
                   help="controller's dynamics: ours, or Franka's Model (its Jacobian, inertia "
                   "and gravity)")
    p.add_argument("--out", type=Path, default=None,
                   help="write DIR/ticks.csv (one row per tick) and DIR/run.json")
    p.add_argument("--budget-ms", type=float, default=1e3 * BUDGET_S,
                   help="per-tick compute budget [ms]: over it on 3 ticks in a row, the loop "
                   "ramps out and stops (keep the default on a robot)")


def _add_pick_place_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--pick", required=True, help="taught pose name, or X,Y,Z [m]")
    p.add_argument("--place", required=True, help="taught pose name, or X,Y,Z [m]")
    p.add_argument("--poses", type=Path, default=None, help="taught poses (JSON, from teach)")
    p.add_argument("--gripper-host", default=None,
                   help="the Franka Hand's address (default: --host)")
    p.add_argument("--lift-m", type=float, default=0.10, help="approach height [m]")
    p.add_argument("--speed-m-s", type=float, default=0.10, help="TCP speed of moves [m/s]")
    p.add_argument("--grasp-width-m", type=float, default=0.04, help="object width [m]")
    p.add_argument("--grasp-epsilon-m", type=float, default=0.005,
                   help="grasp succeeds if the fingers stop within this of the width [m]")
    p.add_argument("--grasp-force-n", type=float, default=40.0, help="squeeze force [N]")


def _vector3(text: str) -> tuple[float, float, float]:
    """``DX,DY,DZ`` [m], each within 0.1 m (a step, not a move)."""
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 3 or not all(abs(v) <= 0.1 for v in values):
        raise argparse.ArgumentTypeError(f"invalid step {text!r}; valid: DX,DY,DZ in metres, "
                                         "each within 0.1")
    return values  # type: ignore[return-value]


def run(args: argparse.Namespace) -> int:
    """Connect and run ``args.command``; returns the exit status."""
    session.check_args(args)
    with session.client_lock(args.host):
        return _run_connected(args)


def _run_connected(args: argparse.Namespace) -> int:
    """``run`` once this process holds the robot (``session.client_lock``)."""
    import numpy as np

    from impact_franka.runner import TargetStep, hold

    _, robot = session.connect(args)
    controller, setup = session.make_controller(args, robot)
    if args.command == "teach":
        return _teach(args, robot, controller)
    failed = ""
    if args.command == "pick-place":
        report, setup["pick_place"], failed = _pick_place(args, robot, controller)
    else:
        step_m = getattr(args, "step_m", None)
        step = None if step_m is None else TargetStep(np.array(step_m), args.step_at_s)
        report = hold(robot, controller, args.seconds, float_only=args.command == "check",
                      torque_source=args.torque_source, step=step,
                      budget_s=1e-3 * getattr(args, "budget_ms", 1e3 * BUDGET_S))
    session.print_report(report)
    if report.stopped_by_signal:
        print("  stopped early on SIGINT/SIGTERM (ramped out, then finished the motion)")
    if getattr(args, "out", None) is not None:
        session.write_outputs(args, report, setup)
    if report.stop_reason == "reflex":
        print(f"impact-robot: the robot stopped the motion: {report.robot_message}; errors: "
              f"{report.robot_errors or 'none'}", file=sys.stderr)
        return 1
    if report.stop_reason == "budget":
        print("impact-robot: stopped: controller compute over the per-tick budget on consecutive "
              "ticks (ramped out)", file=sys.stderr)
        return 1
    if failed and not report.stopped_by_signal:
        print(f"impact-robot: pick-place: {failed}", file=sys.stderr)
        return 1
    return 0 if not report.robot_errors else 1


def _teach(args: argparse.Namespace, robot: object, controller: object) -> int:
    """Float for ``--float-seconds`` (zero torques: the arm is guided by hand), then record
    the TCP pose (our model's, from the measured ``q``) under ``--name``."""
    import numpy as np

    from impact_envs.control.lie import matrix_to_quat
    from impact_franka.fci import reading
    from impact_franka.pick_place import Pose
    from impact_franka.poses import save_pose
    from impact_franka.runner import hold

    if args.float_seconds > 0:
        report = hold(robot, controller, args.float_seconds, float_only=True)
        if report.stop_reason == "reflex":
            print(f"impact-robot: the robot stopped the motion: {report.robot_message}",
                  file=sys.stderr)
            return 1
    q = reading(robot.read_once()).q  # type: ignore[attr-defined]
    arm = controller.dynamics  # type: ignore[attr-defined]
    arm.update(q, np.zeros(7))
    pose = Pose(arm.pos_ee_world.copy(), matrix_to_quat(arm.rot_ee_world))
    save_pose(args.poses, args.name, pose, q)
    print(f"  taught {args.name!r}: TCP {np.round(pose.pos_m, 4).tolist()} m, quaternion "
          f"{np.round(pose.quat_wxyz, 4).tolist()} (w first), saved to {args.poses}")
    return 0


def _pick_place(args: argparse.Namespace, robot: object,
                controller: object) -> tuple[object, dict, str]:
    """Run the pick-and-place sequence; (loop report, what each step did, the first failed
    step's description or "")."""
    import numpy as np

    from impact_envs.control.lie import matrix_to_quat
    from impact_franka.fci import reading
    from impact_franka.gripper import GripperCommand, GripperProcess
    from impact_franka.pick_place import GRIPPER_STEPS, PickPlacePlan, PickPlaceTarget
    from impact_franka.poses import resolve_pose
    from impact_franka.runner import run_loop

    arm = controller.dynamics  # type: ignore[attr-defined]
    arm.update(reading(robot.read_once()).q, np.zeros(7))  # type: ignore[attr-defined]
    quat = matrix_to_quat(arm.rot_ee_world)
    pick, place = (resolve_pose(spec, args.poses, quat) for spec in (args.pick, args.place))
    grasp = GripperCommand("grasp", args.grasp_width_m, 0.1, args.grasp_force_n,
                           args.grasp_epsilon_m, args.grasp_epsilon_m)
    plan = PickPlacePlan(pick, place, grasp, lift_m=args.lift_m,
                         speed_m_per_s=args.speed_m_s)
    gripper = GripperProcess(args.gripper_host or args.host)
    source = PickPlaceTarget(plan, gripper)
    gripper.open()  # a wrong gripper host is one line, before any motion
    report = run_loop(robot, controller, args.seconds, source,  # type: ignore[arg-type]
                      torque_source=args.torque_source, budget_s=1e-3 * args.budget_ms)
    for r in source.records:
        verdict = "ok" if r.ok else "FAILED" if r.name in GRIPPER_STEPS else "short"
        print(f"  {r.name:13s} {r.t_start_s:6.2f}-{r.t_end_s:6.2f} s  {verdict:6s} {r.detail}")
    failed = source.failure
    if not failed and not source.finished:
        failed = f"did not finish within --seconds {args.seconds:g}"
    steps = {"steps": [r._asdict() for r in source.records], "grasped": source.grasped,
             "finished": source.finished, "pick_m": pick.pos_m.tolist(),
             "place_m": place.pos_m.tolist()}
    return report, steps, failed


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        return run(args)
    except ImpactError as exc:
        print(f"impact-robot: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    raise SystemExit(main())
