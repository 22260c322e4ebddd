"""The command-line contract shared by every ``impact-*`` entry point."""

from __future__ import annotations

import argparse
from typing import NoReturn


class OneLineParser(argparse.ArgumentParser):
    """ArgumentParser whose usage errors are one stderr line ``PROG: error: ...``, exit 2
    (argparse's default prints the whole usage first)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")

    def fail(self, message: object) -> NoReturn:
        """Exit 2 with one line naming what is wrong (a refused value, not a usage error)."""
        self.exit(2, f"{self.prog}: error: {message}\n")


def add_robot_set(parser: argparse.ArgumentParser, kept_in: str = "") -> None:
    """``--robot-set FIELD=VALUE`` (repeatable; ``RobotOptions`` fields, e.g. ``realism=fr3``),
    as every entry point that builds a robot takes it; ``kept_in`` names where it is recorded."""
    where = f"; kept in {kept_in}" if kept_in else ""
    parser.add_argument(
        "--robot-set", action="append", default=[], metavar="FIELD=VALUE",
        help="change one field of the simulated robot (RobotOptions; repeatable), e.g. "
             f"realism=fr3 (docs/sensing.md, 'Realism profiles') or delay_ticks=0{where}")
