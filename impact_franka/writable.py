"""Whether a folder can be written, tried for real before the robot is held: ``--out`` of
every command and ``teach --poses`` (``os.access`` says yes for root under ``/proc``)."""

from __future__ import annotations

import contextlib
import os
from pathlib import Path


def try_writing(out: Path) -> None:
    """Create ``out`` (with its missing parents) and a file in it, then remove all of it;
    ``OSError`` (its ``filename`` the path that could not be created) if that fails."""
    absolute = out.absolute()
    missing = [p for p in (absolute, *absolute.parents) if not p.exists()]
    created: list[Path] = []
    try:
        for folder in reversed(missing):
            folder.mkdir()
            created.append(folder)
        probe = absolute / f".impact-robot-probe-{os.getpid()}"
        probe.open("x").close()
        probe.unlink()
    finally:
        for folder in reversed(created):
            with contextlib.suppress(OSError):
                folder.rmdir()
