"""The command-line contract shared by every ``impact-*`` entry point: one-line errors."""

from __future__ import annotations

import argparse
import contextlib
import signal
import threading
from collections.abc import Callable, Iterator
from typing import NoReturn


class OneLineParser(argparse.ArgumentParser):
    """ArgumentParser whose usage errors are one stderr line ``PROG: error: ...``, exit 2
    (argparse's default prints the whole usage first)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")

    def fail(self, message: object) -> NoReturn:
        """Exit 2 with one line naming what is wrong (a refused value, not a usage error)."""
        self.exit(2, f"{self.prog}: error: {message}\n")


@contextlib.contextmanager
def signal_handler(signum: int, handler: Callable[[int, object], object]) -> Iterator[None]:
    """``handler`` for ``signum`` while the block runs, the previous handler back afterwards.
    Python installs handlers from the main thread only: elsewhere the block runs with the
    handlers as they were."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signum, handler)
    try:
        yield
    finally:
        signal.signal(signum, previous)
