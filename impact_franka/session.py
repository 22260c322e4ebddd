"""What every ``impact-robot`` command shares once its arguments passed (checks.py): the
connection (connection.py: one client per robot, a watchdog, pending errors refused unless
``--recover``), the controller with its collision thresholds and model check, and the run's
outputs (``ticks.csv``, ``run.json``, the figure), written in a folder created only then.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from pathlib import Path

from impact_franka.connection import connect
from impact_franka.fci import FrankaError

__all__ = ["connect", "make_controller", "print_report", "write_outputs"]


def print_report(report: object) -> None:
    r = report
    print(f"  loop: {r.ticks} ticks in {r.seconds:.2f} s ({r.rate_hz:.0f} Hz); compute p50 "
          f"{r.compute_p50_us:.0f} us, p99.9 {r.compute_p999_us:.0f} us, max "
          f"{r.compute_max_us:.0f} us")
    print(f"  position error: end of hold {1e3 * r.pos_error_final_m:.2f} mm, max "
          f"{1e3 * r.pos_error_max_m:.2f} mm, after the ramp-out "
          f"{1e3 * r.pos_error_after_ramp_m:.2f} mm; our TCP vs O_T_EE "
          f"{1e3 * r.tcp_vs_robot_m:.2f} mm")
    print(f"  robot errors: {r.robot_errors or 'none'}; command success rate, lowest "
          f"{r.command_success_rate_min:.3f}; cycles unanswered in a row, most "
          f"{r.lost_in_a_row_max} (the robot aborts at 20)")


def make_controller(args: argparse.Namespace, robot: object) -> tuple[object, dict]:
    """The controller for ``args`` and what was set up: collision thresholds, model check."""
    from impact_control.controller import ImpactController
    from impact_control.dynamics import PinocchioArm
    from impact_control.presets import preset_config
    from impact_franka.collision import collision_thresholds
    from impact_franka.fci import fr3_config
    from impact_franka.model import FrankaModelArm, compare_models

    state, ours = robot.read_once(), PinocchioArm()
    franka_model = robot.load_model()
    agreement = compare_models(franka_model, state, ours)
    print(f"  {agreement.line()}")
    for mismatch in agreement.mismatches():
        print(f"  MODEL MISMATCH: {mismatch} (impact_franka.model.TOLERANCE; docs/franka.md)")
    thresholds = collision_thresholds(args.max_payload_kg, ours.jacobian)
    thresholds.apply(robot)
    print(f"  collision thresholds for an undeclared {args.max_payload_kg:g} kg: joints "
          f"{list(thresholds.torque_nm)} Nm, Cartesian {list(thresholds.force)}")
    dynamics = (FrankaModelArm(franka_model, state, PinocchioArm())
                if getattr(args, "model", "pinocchio") == "franka" else ours)
    config = fr3_config(preset_config(getattr(args, "preset", "default")))
    controller = ImpactController(dynamics, config, mode=getattr(args, "controller",
                                                                 "impedance"))
    return controller, {"model_agreement": agreement._asdict(),
                        "collision_thresholds": thresholds._asdict()}


def write_outputs(args: argparse.Namespace, report: object, setup: dict) -> None:
    """``DIR/ticks.csv``, ``DIR/run.json`` (versions, arguments, setup, what the loop
    measured) and ``DIR/protocol.png``/``.pdf`` (impact-protocol's figure); DIR is created
    here, after the run (checks.check_out refused a DIR that holds anything)."""
    out: Path = args.out
    try:
        out.mkdir(parents=True, exist_ok=True)
        _write(args, report, setup, out)
    except OSError as exc:
        raise FrankaError(f"cannot write the run to {out}: {exc.strerror or exc}") from None


def _write(args: argparse.Namespace, report: object, setup: dict, out: Path) -> None:
    from impact_control.runinfo import host_info, package_versions, utc_now
    from impact_franka.figures import plot_ticks

    report.ticks_table.to_csv(out / "ticks.csv", index=False, float_format="%.9g")
    summary = {k: v for k, v in vars(report).items() if k != "ticks_table"}
    run = {"command": "impact-robot " + shlex.join(sys.argv[1:]), "utc": utc_now(),
           "arguments": {k: str(v) for k, v in vars(args).items()},
           "versions": {**package_versions(), "pylibfranka": version("pylibfranka")},
           "robot_protocol": "libfranka's, as spoken by pylibfranka (it refuses a robot "
                             "server of another version when it connects)",
           "host": host_info(), **setup, "report": summary}
    (out / "run.json").write_text(json.dumps(run, indent=2) + "\n")
    figures = plot_ticks(report.ticks_table, getattr(args, "controller", "impedance"), out)
    print(f"  wrote {out / 'ticks.csv'}, {out / 'run.json'} and "
          f"{', '.join(p.name for p in figures)}")


def version(package: str) -> str | None:
    from importlib import metadata

    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return None


