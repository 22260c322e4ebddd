"""Shared by the tests of ``impact-robot``'s refusals: run the CLI in-process with the
connection replaced by a sentinel, so a case that got past the checks shows as exit 1 with
"CONNECT CALLED" instead of dialling anything."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from impact_franka.fci import FrankaError

SENTINEL = "CONNECT CALLED"
DOWN = [0.0, 1.0, 0.0, 0.0]


def no_connect(monkeypatch: pytest.MonkeyPatch) -> None:
    """Make any connection attempt fail loudly (exit 1 naming ``SENTINEL``)."""
    from impact_franka import session

    def refuse(args: object) -> None:
        raise FrankaError(SENTINEL)

    monkeypatch.setattr(session, "connect", refuse)


def run_cli(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    """(exit status, stderr) of ``impact-robot argv``; stdout must stay empty."""
    from impact_franka.cli import main

    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own refusals
        code = int(exc.code or 0)
    captured = capsys.readouterr()
    return code, captured.err


def assert_refused(code: int, err: str, message: str = "") -> None:
    """Exit 2, one line on stderr, naming ``message``, nothing connected."""
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith("impact-robot"), err
    assert "Traceback" not in err and SENTINEL not in err
    assert message in err, err


def write_poses(path: Path, entries: dict) -> str:
    """Write a poses file; its bytes (to check it is unchanged afterwards)."""
    text = json.dumps(entries)
    path.write_text(text)
    return text


def pose(x: float = 0.5, y: float = 0.0, z: float = 0.3) -> dict:
    """A valid taught entry."""
    return {"pos_m": [x, y, z], "quat_wxyz": DOWN, "q_rad": [0.0] * 7}
