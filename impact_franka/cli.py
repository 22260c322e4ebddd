"""``impact-robot``: IMPACT on an FR3 (or a libfranka-protocol simulator) through pylibfranka.

    impact-robot check --host HOST [--seconds S]
        connect, print the robot mode and errors, our model against Franka's at the current
        configuration, our TCP against the robot's O_T_EE, and the loop timing over S seconds
        of zero torques (the robot's gravity compensation alone)
    impact-robot hold --host HOST [--controller impact|impedance]
                      [--preset default|paper|keep_carried|lift_watch|authors_real]
                      [--model pinocchio|franka] [--max-payload-kg KG] [--seconds S]
                      [--step-m DX,DY,DZ [--step-at-s T]] [--out DIR]
        hold the current TCP pose with the FR3 configuration (fci.fr3_config); DIR (new or
        empty, created after the run) gets ticks.csv (one row per control tick), run.json and
        protocol.png/.pdf
    impact-robot teach --host HOST --poses FILE --name NAME [--float-seconds S] [--replace]
        float the arm for S seconds (zero torques: guide it by hand), then record its TCP
        pose under NAME in FILE (a NAME already there only with --replace)
    impact-robot pick-place --host HOST --pick NAME|X,Y,Z --place NAME|X,Y,Z [--poses FILE]
                      [--gripper-host HOST] [--grasp-width-m W] [--controller ...] [--out DIR]
        the paper's dumbbell task: open, pick the object at --pick, carry it to --place,
        release, retreat (pick_place.py), the Franka Hand through pylibfranka's Gripper

Every argument is checked before anything connects (checks.py): each number finite and in
its range, the pose file readable (pick-place) or writable (teach), every pose in the FR3's
workspace (poses.check_workspace), ``--host`` a host name or IP address without a port,
``--out`` new or empty and writable (tried: created and removed). Then the command takes the
one-client lock for the robot (connection.py), gives up on a robot that does not answer
within ``--connect-timeout-s`` (10 s), sets the collision thresholds for ``--max-payload-kg``
(collision.py) and refuses to start while the robot reports errors unless ``--recover``
(libfranka's automatic error recovery). Exit 0 after a clean finish; 2 with one line on a bad
argument (nothing connected, nothing written); 1 with one line naming the robot's errors, the
failed step or why the robot could not be reached otherwise; 130 / 143 with one line on
Ctrl-C / SIGTERM outside the control loop (a probe's child is ended before the lock is
released). A real robot needs a real-time kernel (``--realtime enforce``).
"""

from __future__ import annotations

import argparse
import signal
import sys

from impact_control.cli import OneLineParser, signal_handler
from impact_control.controller import CONTROLLERS
from impact_control.errors import ImpactError, InvalidArgumentError
from impact_control.presets import ROBOT_PRESETS, check_robot_preset
from impact_franka import checks
from impact_franka.checks import MAX_SECONDS, host, number, pose_name
from impact_franka.commands import run
from impact_franka.connection import CONNECT_TIMEOUT_S
from impact_franka.fci import TORQUE_SOURCES
from impact_franka.runner import BUDGET_S

REALTIME = ("ignore", "enforce")
MODELS = ("pinocchio", "franka")
COMMANDS = {  # name: (one line for the list, the subcommand's description)
    "check": ("connect, compare the models, time a zero-torque loop",
              "Connect, print the robot's mode and errors, our model against Franka's and our "
              "TCP against O_T_EE, then time the loop over --seconds of zero torques (the "
              "robot's own gravity compensation holds the arm)."),
    "hold": ("hold the TCP pose with IMPACT or impedance",
             "Hold the current TCP pose with IMPACT (or impedance alone) for --seconds; "
             "--step-m moves the target once; --out DIR gets ticks.csv, run.json and "
             "protocol.png/.pdf."),
    "teach": ("float the arm, record its TCP pose by name",
              "Float the arm for --float-seconds (guide it by hand), then record its TCP pose "
              "under --name in the --poses JSON file."),
    "pick-place": ("the dumbbell task with the Franka Hand",
                   "The paper's dumbbell task with the Franka Hand: open, pick the object at "
                   "--pick, carry it to --place, release, retreat."),
}


def _parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="impact-robot", description="IMPACT on an FR3 (or a "
                           "libfranka-protocol simulator) through pylibfranka.",
                           epilog="Exit 0: done; 1: the robot stopped, refused or could not "
                           "be reached; 2: a bad argument (nothing connected). docs/franka.md")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, (short, about) in COMMANDS.items():
        p = sub.add_parser(name, help=short, description=about)
        _add_common_arguments(p, name)
        if name in ("hold", "pick-place"):
            _add_run_arguments(p)
        if name == "hold":
            p.add_argument("--step-m", type=checks.step, default=None, metavar="DX,DY,DZ",
                           help="move the held target by this offset [m, base frame] once")
            p.add_argument("--step-at-s", metavar="S", type=number(0.0, MAX_SECONDS), default=None,
                           help="when the step happens [s into the hold, < --seconds; "
                           "default 1, or half of --seconds if shorter]")
        if name == "teach":
            p.add_argument("--poses", metavar="FILE", type=checks.path, required=True,
                           help="taught poses (JSON; created if missing)")
            p.add_argument("--name", metavar="NAME", type=pose_name, required=True,
                           help="name of the pose to record (a letter or _ first)")
            p.add_argument("--replace", action="store_true",
                           help="overwrite a pose of that name already in --poses")
            p.add_argument("--float-seconds", metavar="S", type=number(0.0, MAX_SECONDS),
                           default=0.0,
                           help="float the arm (zero torques) this long before recording")
        if name == "pick-place":
            _add_pick_place_arguments(p)
    return parser


def _add_common_arguments(p: argparse.ArgumentParser, name: str) -> None:
    p.add_argument("--host", type=host, required=True,
                   help="robot (FCI) address, e.g. 172.16.0.2")
    p.add_argument("--seconds", metavar="S", type=number(0.0, MAX_SECONDS, low_open=True),
                   default=60.0 if name == "pick-place" else 2.0,
                   help=f"length of the run, up to {MAX_SECONDS:g} (pick-place: the longest it "
                   "may take)")
    p.add_argument("--connect-timeout-s", metavar="S", type=number(0.5, 300.0),
                   default=CONNECT_TIMEOUT_S,
                   help="give up on a robot that does not answer within this [s]")
    p.add_argument("--realtime", choices=REALTIME, default="ignore",
                   help="libfranka RealtimeConfig (enforce: needs a real-time kernel)")
    p.add_argument("--max-payload-kg", metavar="KG", type=number(0.0, 20.0), default=0.0,
                   help="largest load handed over without set_load, 0 to 20; raises the "
                   "collision thresholds by 1.5x what it reads (docs/franka.md)")
    p.add_argument("--torque-source", choices=TORQUE_SOURCES, default="tau_J",
                   help="measured joint torque: tau_J (an FR3) or tau_J+g (a simulator "
                   "whose tau_J leaves gravity out, e.g. franka-sim)")
    p.add_argument("--recover", action="store_true",
                   help="call automatic_error_recovery if the robot reports errors")
    p.add_argument("--budget-ms", metavar="MS", type=number(0.05, 10.0), default=1e3 * BUDGET_S,
                   help="per-tick compute budget [ms], 0.05 to 10: over it on 3 ticks in a "
                   "row, the loop ramps out and stops (keep the default on a robot)")


def _robot_preset(text: str) -> str:
    """An argparse ``type``: a preset that may run on an FR3 (``presets.ROBOT_PRESETS``)."""
    try:
        return check_robot_preset(text)
    except InvalidArgumentError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _add_run_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--controller", choices=CONTROLLERS, default="impact",
                   help="impact: impedance + learned feedforward (default); impedance: the "
                   "same estimator, no feedforward")
    p.add_argument("--preset", type=_robot_preset, default="default",
                   metavar="{" + ",".join(ROBOT_PRESETS) + "}",
                   help="controller configuration: default (what we ship), paper (the "
                   "paper's table read literally) or authors_real (the authors' released "
                   "controller with their robot's values; authors_sim is refused: it runs only "
                   "in simulation); docs/controller.md")
    p.add_argument("--model", choices=MODELS, default="pinocchio",
                   help="controller's dynamics: ours, or Franka's Model (its Jacobian, inertia "
                   "and gravity)")
    p.add_argument("--out", metavar="DIR", type=checks.path, default=None,
                   help="write DIR/ticks.csv (one row per tick) and DIR/run.json (DIR: new or "
                   "empty)")


def _add_pick_place_arguments(p: argparse.ArgumentParser) -> None:
    for flag in ("--pick", "--place"):
        p.add_argument(flag, metavar="NAME|X,Y,Z", required=True,
                       help="taught pose name (with --poses), or X,Y,Z [m, base frame]")
    p.add_argument("--poses", metavar="FILE", type=checks.path, default=None,
                   help="taught poses (JSON, from teach)")
    p.add_argument("--gripper-host", metavar="HOST", type=host, default=None,
                   help="the Franka Hand's address (default: --host)")
    p.add_argument("--lift-m", metavar="M", type=number(0.0, 0.3), default=0.10,
                   help="approach height [m], 0 to 0.3")
    p.add_argument("--speed-m-s", metavar="M_S", type=number(0.01, 0.5), default=0.10,
                   help="TCP speed of moves [m/s], 0.01 to 0.5")
    p.add_argument("--grasp-width-m", metavar="M", type=number(0.0, 0.08), default=0.04,
                   help="object width [m], 0 to 0.08 (the hand's stroke)")
    p.add_argument("--grasp-epsilon-m", metavar="M", type=number(0.0, 0.08), default=0.005,
                   help="grasp succeeds if the fingers stop within this of the width [m]")
    p.add_argument("--grasp-force-n", metavar="N", type=number(1.0, 140.0), default=40.0,
                   help="squeeze force [N], 1 to 140")


class Terminated(KeyboardInterrupt):
    """SIGTERM outside the control loop, raised like Ctrl-C's ``KeyboardInterrupt`` so that
    what the command started (the connection probe's child) ends and the one-client lock is
    released on the way out, in that order (the loop itself handles both signals: runner.py)."""


def _raise_terminated(signum: int, frame: object) -> None:
    raise Terminated


def main(argv: list[str] | None = None) -> int:
    """``impact-robot``: exit 0 done, 1 the robot stopped, refused or was not reached, 2 a bad
    argument (argparse's own errors, and ``InvalidArgumentError`` from checks.py), 130 / 143
    Ctrl-C / SIGTERM outside the control loop, each with one line on stderr."""
    args = _parser().parse_args(argv)
    try:
        with signal_handler(signal.SIGTERM, _raise_terminated):
            return run(args)
    except InvalidArgumentError as exc:
        print(f"impact-robot: {exc}", file=sys.stderr)
        return 2
    except ImpactError as exc:
        print(f"impact-robot: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as exc:
        term = isinstance(exc, Terminated)
        print(f"impact-robot: {'terminated (SIGTERM)' if term else 'interrupted'} outside the "
              "control loop (no torque command was running)", file=sys.stderr)
        return 128 + (signal.SIGTERM if term else signal.SIGINT)


if __name__ == "__main__":
    raise SystemExit(main())
