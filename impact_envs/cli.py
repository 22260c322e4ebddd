"""Command-line options shared by the entry points that build a simulated robot."""

from __future__ import annotations

import argparse


def robot_set_help(kept_in: str = "") -> str:
    """The help of ``--robot-set``; ``kept_in`` names where it is recorded."""
    where = f"; kept in {kept_in}" if kept_in else ""
    return ("change one field of the simulated robot (RobotOptions; repeatable), e.g. "
            f"realism=fr3 (docs/sensing.md, 'Realism profiles') or delay_ticks=0{where}")


def add_robot_set(parser: argparse.ArgumentParser, kept_in: str = "") -> None:
    """``--robot-set FIELD=VALUE`` (repeatable; ``RobotOptions`` fields, e.g. ``realism=fr3``),
    as every entry point that builds a robot takes it; ``kept_in`` names where it is recorded."""
    parser.add_argument("--robot-set", action="append", default=[], metavar="FIELD=VALUE",
                        help=robot_set_help(kept_in))
