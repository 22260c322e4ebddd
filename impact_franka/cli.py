"""``impact-robot``: IMPACT on an FR3 (or a libfranka-protocol simulator) through pylibfranka.

    impact-robot check --host HOST [--seconds S]
        connect, print the robot mode and errors, our TCP against the robot's O_T_EE, and the
        loop timing over S seconds of zero torques (the robot's gravity compensation alone)
    impact-robot hold --host HOST [--controller impact|impedance] [--seconds S] [--out DIR]
        hold the current TCP pose with the FR3 configuration (fci.fr3_config); DIR gets
        ticks.csv (one row per control tick) and run.json

Exit 0 after a clean finish; 1 with one line naming the robot's errors otherwise; 2 on bad
arguments. A real robot needs a real-time kernel (``--realtime enforce``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from impact_envs.errors import ImpactError

CONTROLLERS = ("impact", "impedance")
REALTIME = ("ignore", "enforce")


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="impact-robot", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    for name in ("check", "hold"):
        p = sub.add_parser(name)
        p.add_argument("--host", required=True, help="robot (FCI) address, e.g. 172.16.0.2")
        p.add_argument("--seconds", type=float, default=2.0)
        p.add_argument("--realtime", choices=REALTIME, default="ignore",
                       help="libfranka RealtimeConfig (enforce: needs a real-time kernel)")
        if name == "hold":
            p.add_argument("--controller", choices=CONTROLLERS, default="impact")
            p.add_argument("--out", type=Path, default=None,
                           help="write DIR/ticks.csv (one row per tick) and DIR/run.json")
    return parser


def _print_report(report: object) -> None:
    r = report
    print(f"  loop: {r.ticks} ticks in {r.seconds:.2f} s ({r.rate_hz:.0f} Hz); compute p50 "
          f"{r.compute_p50_us:.0f} us, p99.9 {r.compute_p999_us:.0f} us, max "
          f"{r.compute_max_us:.0f} us")
    print(f"  position error: final {1e3 * r.pos_error_final_m:.2f} mm, max "
          f"{1e3 * r.pos_error_max_m:.2f} mm; our TCP vs O_T_EE {1e3 * r.tcp_vs_robot_m:.2f} mm")
    print(f"  robot errors: {r.robot_errors or 'none'}")


def run(args: argparse.Namespace) -> int:
    """Connect and run ``args.command``; returns the exit status."""
    if not args.seconds > 0:
        raise ImpactError(f"invalid --seconds {args.seconds!r}; valid: > 0")
    out = getattr(args, "out", None)
    if out is not None:  # before the robot moves: a run must not end unable to save its log
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ImpactError(f"invalid --out {out}: {exc.strerror}; valid: a writable "
                              "directory") from None
    try:
        import pylibfranka as plf
    except ImportError:
        raise ImpactError("impact-robot needs pylibfranka: pip install -e '.[franka]'") from None

    from impact_envs.control.controller import ImpactController
    from impact_envs.robot.dynamics import PinocchioArm
    from impact_franka.fci import fr3_config
    from impact_franka.runner import hold

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
    mode = getattr(args, "controller", "impedance")
    controller = ImpactController(PinocchioArm(), fr3_config(), mode=mode)
    report = hold(robot, controller, args.seconds, float_only=args.command == "check")
    _print_report(report)
    if report.stopped_by_signal:
        print("  stopped early on SIGINT/SIGTERM (ramped out, then finished the motion)")
    if getattr(args, "out", None) is not None:
        _write_outputs(args, report)
    if report.stop_reason == "budget":
        print("impact-robot: stopped: controller compute over the per-tick budget on consecutive "
              "ticks (ramped out)", file=sys.stderr)
        return 1
    return 0 if not report.robot_errors else 1


def _write_outputs(args: argparse.Namespace, report: object) -> None:
    """``DIR/ticks.csv`` and ``DIR/run.json`` (versions, arguments, what the loop measured)."""
    from impact_eval.runinfo import host_info, package_versions, utc_now

    out: Path = args.out
    report.ticks_table.to_csv(out / "ticks.csv", index=False, float_format="%.9g")
    summary = {k: v for k, v in vars(report).items() if k != "ticks_table"}
    run = {"command": "impact-robot " + " ".join(sys.argv[1:]), "utc": utc_now(),
           "arguments": {k: str(v) for k, v in vars(args).items()},
           "versions": package_versions(), "host": host_info(), "report": summary}
    (out / "run.json").write_text(json.dumps(run, indent=2) + "\n")
    print(f"  wrote {out / 'ticks.csv'} and {out / 'run.json'}")


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        return run(args)
    except ImpactError as exc:
        print(f"impact-robot: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    raise SystemExit(main())
