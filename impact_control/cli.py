"""The command-line contract shared by every ``impact-*`` entry point: one-line errors."""

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
