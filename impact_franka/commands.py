"""What each ``impact-robot`` command does once its arguments passed ``checks.check_args``:
take the one-client lock, connect, run the loop (or teach, or pick and place), report, and
return the exit status (cli.py's docstring)."""

from __future__ import annotations

import argparse
import sys

from impact_franka import checks, session
from impact_franka.connection import client_lock
from impact_franka.pick_place import Pose


def run(args: argparse.Namespace) -> int:
    """Check ``args`` (``InvalidArgumentError`` before anything connects), then connect and
    run ``args.command``; returns the exit status."""
    targets = checks.check_args(args)
    if args.command == "hold" and args.step_m is not None and args.step_at_s is None:
        args.step_at_s = min(1.0, args.seconds / 2.0)
    with client_lock(args.host):
        return _run_connected(args, targets)


def _run_connected(args: argparse.Namespace, targets: dict[str, Pose]) -> int:
    """``run`` once this process holds the robot (``connection.client_lock``)."""
    import numpy as np

    from impact_franka.runner import TargetStep, hold

    _, robot = session.connect(args)
    controller, setup = session.make_controller(args, robot)
    if args.command == "teach":
        return _teach(args, robot, controller)
    failed = ""
    if args.command == "pick-place":
        report, setup["pick_place"], failed = _pick_place(args, targets, robot, controller)
    else:
        step_m = getattr(args, "step_m", None)
        step = None if step_m is None else TargetStep(np.array(step_m), args.step_at_s)
        report = hold(robot, controller, args.seconds, float_only=args.command == "check",
                      torque_source=args.torque_source, step=step,
                      budget_s=1e-3 * args.budget_ms)
    session.print_report(report)
    if report.stopped_by_signal:
        print("  stopped early on SIGINT/SIGTERM (ramped out, then finished the motion)")
    if getattr(args, "out", None) is not None:
        session.write_outputs(args, report, setup)
    return _verdict(report, failed)


def _verdict(report: object, failed: str) -> int:
    """The exit status of a finished loop, with one line on stderr unless 0."""
    r = report
    if r.stop_reason == "reflex":  # type: ignore[attr-defined]
        print(f"impact-robot: the robot stopped the motion: {r.robot_message}; errors: "  # type: ignore[attr-defined]
              f"{r.robot_errors or 'none'}", file=sys.stderr)  # type: ignore[attr-defined]
        return 1
    if r.stop_reason == "budget":  # type: ignore[attr-defined]
        print("impact-robot: stopped: controller compute over the per-tick budget on consecutive "
              "ticks (ramped out)", file=sys.stderr)
        return 1
    if failed and not r.stopped_by_signal:  # type: ignore[attr-defined]
        print(f"impact-robot: pick-place: {failed}", file=sys.stderr)
        return 1
    if r.robot_errors:  # type: ignore[attr-defined]
        print(f"impact-robot: the robot reports errors after the run: {r.robot_errors}",  # type: ignore[attr-defined]
              file=sys.stderr)
        return 1
    return 0


def _teach(args: argparse.Namespace, robot: object, controller: object) -> int:
    """Float for ``--float-seconds`` (zero torques: the arm is guided by hand), then record
    the TCP pose (our model's, from the measured ``q``) under ``--name``."""
    import numpy as np

    from impact_control.lie import matrix_to_quat
    from impact_franka.fci import reading
    from impact_franka.poses import save_pose
    from impact_franka.runner import hold

    if args.float_seconds > 0:
        report = hold(robot, controller, args.float_seconds, float_only=True,
                      budget_s=1e-3 * args.budget_ms)
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


def _pick_place(args: argparse.Namespace, targets: dict[str, Pose], robot: object,
                controller: object) -> tuple[object, dict, str]:
    """Run the pick-and-place sequence; (loop report, what each step did, the first failed
    step's description or "")."""
    import numpy as np

    from impact_control.lie import matrix_to_quat
    from impact_franka.fci import reading
    from impact_franka.gripper import GripperCommand, GripperProcess
    from impact_franka.pick_place import GRIPPER_STEPS, PickPlacePlan, PickPlaceTarget
    from impact_franka.runner import run_loop

    arm = controller.dynamics  # type: ignore[attr-defined]
    arm.update(reading(robot.read_once()).q, np.zeros(7))  # type: ignore[attr-defined]
    quat = matrix_to_quat(arm.rot_ee_world)
    pick, place = (Pose(t.pos_m, quat if t.quat_wxyz is None else t.quat_wxyz)
                   for t in (targets["pick"], targets["place"]))  # checked before connecting
    grasp = GripperCommand("grasp", args.grasp_width_m, 0.1, args.grasp_force_n,
                           args.grasp_epsilon_m, args.grasp_epsilon_m)
    plan = PickPlacePlan(pick, place, grasp, lift_m=args.lift_m,
                         speed_m_per_s=args.speed_m_s)
    gripper = GripperProcess(args.gripper_host or args.host)
    source = PickPlaceTarget(plan, gripper)
    gripper.open(args.connect_timeout_s)  # a wrong gripper host: one line, before any motion
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
