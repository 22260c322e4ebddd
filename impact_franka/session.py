"""What every ``impact-robot`` command shares: checking arguments before connecting, the
connection (pending errors refused unless ``--recover``), the controller with its collision
thresholds and model check, and the run's outputs (``ticks.csv``, ``run.json``, the figure).
"""

from __future__ import annotations

import argparse
import contextlib
import fcntl
import json
import os
import re
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

from impact_envs.errors import ImpactError


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
          f"{r.command_success_rate_min:.3f}")


def check_args(args: argparse.Namespace) -> None:
    """One-line errors before anything connects (a run must not end unable to save its log)."""
    if not args.seconds > 0:
        raise ImpactError(f"invalid --seconds {args.seconds!r}; valid: > 0")
    step_at = getattr(args, "step_at_s", 0.0)
    if getattr(args, "step_m", None) is not None and not 0.0 <= step_at < args.seconds:
        raise ImpactError(f"invalid --step-at-s {step_at!r}; valid: 0 <= value < --seconds")
    if args.command == "teach":
        from impact_franka.poses import check_writable

        if not args.float_seconds >= 0:
            raise ImpactError(f"invalid --float-seconds {args.float_seconds!r}; valid: >= 0")
        check_writable(args.poses)
    if args.command == "pick-place":
        _check_pick_place(args)
    budget = getattr(args, "budget_ms", 0.8)
    if not 0.05 <= budget <= 10.0:
        raise ImpactError(f"invalid --budget-ms {budget!r}; valid: 0.05 to 10")
    if not 0.0 <= args.max_payload_kg <= 20.0:
        raise ImpactError(f"invalid --max-payload-kg {args.max_payload_kg!r}; valid: 0 to 20")
    out = getattr(args, "out", None)
    if out is not None:
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ImpactError(f"invalid --out {out}: {exc.strerror}; valid: a writable "
                              "directory") from None


_PICK_PLACE_RANGES = {"lift_m": (0.0, 0.3), "speed_m_s": (0.01, 0.5),
                      "grasp_width_m": (0.0, 0.08), "grasp_epsilon_m": (0.0, 0.08),
                      "grasp_force_n": (1.0, 140.0)}
"""Valid ranges of pick-place's numbers (the Franka Hand: 8 cm stroke, 140 N peak force)."""


def _check_pick_place(args: argparse.Namespace) -> None:
    for name, (low, high) in _PICK_PLACE_RANGES.items():
        value = getattr(args, name)
        if not low <= value <= high:
            flag = "--" + name.replace("_", "-")
            raise ImpactError(f"invalid {flag} {value!r}; valid: {low:g} to {high:g}")
    import numpy as np

    from impact_franka.poses import resolve_pose

    for flag in ("pick", "place"):
        spec = getattr(args, flag)
        if len(spec.split(",")) != 3 and args.poses is None:
            raise ImpactError(f"invalid --{flag} {spec!r}; valid: X,Y,Z in metres, or a pose "
                              "name with --poses FILE")
        resolve_pose(spec, args.poses, np.array([1.0, 0.0, 0.0, 0.0]))  # names, file, reach


@contextlib.contextmanager
def client_lock(host: str) -> Iterator[None]:
    """One ``impact-robot`` per robot on this machine: an exclusive lock on a file named after
    ``host`` for the whole command. The FCI serves one controlling client; neither simulator
    refuses a second one (measured: both ran two torque loops at once), so a second run here
    is refused with one line before it connects."""
    name = re.sub(r"[^A-Za-z0-9_.-]", "_", host)
    path = Path(tempfile.gettempdir()) / f"impact-robot-{name}.lock"
    with open(path, "a+") as f:
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            f.seek(0)
            owner = f.read().strip() or "?"
            raise ImpactError(f"another impact-robot (PID {owner}) is connected to {host}; "
                              "valid: one client per robot, stop it first") from None
        f.truncate(0)
        f.write(str(os.getpid()))
        f.flush()
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def connect(args: argparse.Namespace) -> tuple[object, object]:
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


def make_controller(args: argparse.Namespace, robot: object) -> tuple[object, dict]:
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


def write_outputs(args: argparse.Namespace, report: object, setup: dict) -> None:
    """``DIR/ticks.csv``, ``DIR/run.json`` (versions, arguments, setup, what the loop
    measured) and ``DIR/protocol.png``/``.pdf`` (impact-protocol's figure)."""
    from impact_eval.runinfo import host_info, package_versions, utc_now
    from impact_franka.figures import plot_ticks

    out: Path = args.out
    report.ticks_table.to_csv(out / "ticks.csv", index=False, float_format="%.9g")
    summary = {k: v for k, v in vars(report).items() if k != "ticks_table"}
    run = {"command": "impact-robot " + " ".join(sys.argv[1:]), "utc": utc_now(),
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


