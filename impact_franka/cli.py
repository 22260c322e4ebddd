"""``impact-robot``: IMPACT on an FR3 (or a libfranka-protocol simulator) through pylibfranka.

    impact-robot check --host HOST [--seconds S]
        connect, print the robot mode and errors, our model against Franka's at the current
        configuration, our TCP against the robot's O_T_EE, and the loop timing over S seconds
        of zero torques (the robot's gravity compensation alone)
    impact-robot hold --host HOST [--controller impact|impedance] [--preset default|paper]
                      [--model pinocchio|franka] [--max-payload-kg KG] [--seconds S] [--out DIR]
        hold the current TCP pose with the FR3 configuration (fci.fr3_config); DIR gets
        ticks.csv (one row per control tick), run.json and protocol.png/.pdf

Both set the collision thresholds for ``--max-payload-kg`` (collision.py) and refuse to start
while the robot reports errors unless ``--recover`` (libfranka's automatic error recovery).
Exit 0 after a clean finish; 1 with one line naming the robot's errors otherwise; 2 on bad
arguments. A real robot needs a real-time kernel (``--realtime enforce``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from impact_envs.cli import OneLineParser
from impact_envs.control.controller import CONTROLLERS
from impact_envs.control.presets import PRESETS
from impact_envs.errors import ImpactError
from impact_franka.fci import TORQUE_SOURCES

REALTIME = ("ignore", "enforce")
MODELS = ("pinocchio", "franka")


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="impact-robot", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    for name in ("check", "hold"):
        p = sub.add_parser(name)
        p.add_argument("--host", required=True, help="robot (FCI) address, e.g. 172.16.0.2")
        p.add_argument("--seconds", type=float, default=2.0)
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
        if name == "hold":
            p.add_argument("--controller", choices=CONTROLLERS, default="impact")
            p.add_argument("--preset", choices=PRESETS, default="default")
            p.add_argument("--step-m", type=_vector3, default=None, metavar="DX,DY,DZ",
                           help="move the held target by this offset [m, base frame] once")
            p.add_argument("--step-at-s", type=float, default=1.0,
                           help="when the step happens [s into the hold]")
            p.add_argument("--model", choices=MODELS, default="pinocchio",
                           help="controller's dynamics: ours, or Franka's Model (its Jacobian, "
                           "inertia and gravity)")
            p.add_argument("--out", type=Path, default=None,
                           help="write DIR/ticks.csv (one row per tick) and DIR/run.json")
    return parser


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


def _print_report(report: object) -> None:
    r = report
    print(f"  loop: {r.ticks} ticks in {r.seconds:.2f} s ({r.rate_hz:.0f} Hz); compute p50 "
          f"{r.compute_p50_us:.0f} us, p99.9 {r.compute_p999_us:.0f} us, max "
          f"{r.compute_max_us:.0f} us")
    print(f"  position error: end of hold {1e3 * r.pos_error_final_m:.2f} mm, max "
          f"{1e3 * r.pos_error_max_m:.2f} mm, after the ramp-out "
          f"{1e3 * r.pos_error_after_ramp_m:.2f} mm; our TCP vs O_T_EE "
          f"{1e3 * r.tcp_vs_robot_m:.2f} mm")
    print(f"  robot errors: {r.robot_errors or 'none'}; command success rate, lowest "
          f"{r.command_success_rate_min:.3f}")


def _check_args(args: argparse.Namespace) -> None:
    """One-line errors before anything connects (a run must not end unable to save its log)."""
    if not args.seconds > 0:
        raise ImpactError(f"invalid --seconds {args.seconds!r}; valid: > 0")
    step_at = getattr(args, "step_at_s", 0.0)
    if getattr(args, "step_m", None) is not None and not 0.0 <= step_at < args.seconds:
        raise ImpactError(f"invalid --step-at-s {step_at!r}; valid: 0 <= value < --seconds")
    if not 0.0 <= args.max_payload_kg <= 20.0:
        raise ImpactError(f"invalid --max-payload-kg {args.max_payload_kg!r}; valid: 0 to 20")
    out = getattr(args, "out", None)
    if out is not None:
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ImpactError(f"invalid --out {out}: {exc.strerror}; valid: a writable "
                              "directory") from None


def _connect(args: argparse.Namespace) -> tuple[object, object]:
    """(pylibfranka module, Robot) with no errors pending (recovered on ``--recover``)."""
    try:
        import pylibfranka as plf
    except ImportError:
        raise ImpactError("impact-robot needs pylibfranka: pip install -e '.[franka]'") from None
    config = (plf.RealtimeConfig.kEnforce if args.realtime == "enforce"
              else plf.RealtimeConfig.kIgnore)
    try:
        robot = plf.Robot(args.host, config)
    except (plf.FrankaException, RuntimeError) as exc:  # pylibfranka's errors are RuntimeErrors
        msg = " ".join(str(exc).split())
        raise ImpactError(f"cannot connect to {args.host}: {msg}") from None
    state = robot.read_once()
    print(f"impact-robot: {args.host}: mode {state.robot_mode}, errors "
          f"{state.current_errors or 'none'}")
    if state.current_errors:
        if not args.recover:
            raise ImpactError(f"the robot reports errors {state.current_errors}; valid: clear "
                              "them, or --recover (libfranka's automatic error recovery)")
        robot.automatic_error_recovery()
        print(f"  recovered: errors now {robot.read_once().current_errors or 'none'}")
    return plf, robot


def _controller(args: argparse.Namespace, robot: object) -> tuple[object, dict]:
    """The controller for ``args`` and what was set up: collision thresholds, model check."""
    from impact_envs.control.controller import ImpactController
    from impact_envs.control.presets import preset_config
    from impact_envs.robot.dynamics import PinocchioArm
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


def run(args: argparse.Namespace) -> int:
    """Connect and run ``args.command``; returns the exit status."""
    import numpy as np

    from impact_franka.runner import TargetStep, hold

    _check_args(args)
    step_m = getattr(args, "step_m", None)
    step = None if step_m is None else TargetStep(np.array(step_m), args.step_at_s)
    _, robot = _connect(args)
    controller, setup = _controller(args, robot)
    report = hold(robot, controller, args.seconds, float_only=args.command == "check",
                  torque_source=args.torque_source, step=step)
    _print_report(report)
    if report.stopped_by_signal:
        print("  stopped early on SIGINT/SIGTERM (ramped out, then finished the motion)")
    if getattr(args, "out", None) is not None:
        _write_outputs(args, report, setup)
    if report.stop_reason == "reflex":
        print(f"impact-robot: the robot stopped the motion: {report.robot_message}; errors: "
              f"{report.robot_errors or 'none'}", file=sys.stderr)
        return 1
    if report.stop_reason == "budget":
        print("impact-robot: stopped: controller compute over the per-tick budget on consecutive "
              "ticks (ramped out)", file=sys.stderr)
        return 1
    return 0 if not report.robot_errors else 1


def _write_outputs(args: argparse.Namespace, report: object, setup: dict) -> None:
    """``DIR/ticks.csv``, ``DIR/run.json`` (versions, arguments, setup, what the loop
    measured) and ``DIR/protocol.png``/``.pdf`` (impact-protocol's figure)."""
    from impact_eval.runinfo import host_info, package_versions, utc_now
    from impact_franka.figures import plot_ticks

    out: Path = args.out
    report.ticks_table.to_csv(out / "ticks.csv", index=False, float_format="%.9g")
    summary = {k: v for k, v in vars(report).items() if k != "ticks_table"}
    run = {"command": "impact-robot " + " ".join(sys.argv[1:]), "utc": utc_now(),
           "arguments": {k: str(v) for k, v in vars(args).items()},
           "versions": {**package_versions(), "pylibfranka": _version("pylibfranka")},
           "robot_protocol": "libfranka's, as spoken by pylibfranka (it refuses a robot "
                             "server of another version when it connects)",
           "host": host_info(), **setup, "report": summary}
    (out / "run.json").write_text(json.dumps(run, indent=2) + "\n")
    figures = plot_ticks(report.ticks_table, getattr(args, "controller", "impedance"), out)
    print(f"  wrote {out / 'ticks.csv'}, {out / 'run.json'} and "
          f"{', '.join(p.name for p in figures)}")


def _version(package: str) -> str | None:
    from importlib import metadata

    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return None


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        return run(args)
    except ImpactError as exc:
        print(f"impact-robot: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    raise SystemExit(main())
