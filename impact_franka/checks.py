"""``impact-robot``'s arguments, checked before anything connects: a bad argument is one line
and exit 2, and nothing is created, changed or left behind.

Each value is checked where argparse reads it (``number``, ``host``, ``pose_name``: a finite
number in its range, a host name or IP address without a port, a pose name); what depends on
several flags or on files is checked by ``check_args`` after parsing (``--step-at-s`` with
``--step-m`` and within ``--seconds``, the ``--poses`` file, the pick and place poses in the
workspace, ``--out``).
Both raise ``InvalidArgumentError``, which the CLI turns into exit 2.
"""

from __future__ import annotations

import argparse
import ipaddress
import math
import re
from collections.abc import Callable
from pathlib import Path

from impact_control.errors import InvalidArgumentError
from impact_franka.pick_place import Pose
from impact_franka.writable import try_writing

MAX_SECONDS = 600.0
"""Longest run [s]: every 1 ms tick is kept in memory until the run ends (measured 600 B
per tick as Python rows, 0.36 GB at 600 s), then written to ticks.csv."""
_LABEL = re.compile(r"[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?")
"""One label of a host name (RFC 1123: letters, digits, inner hyphens, up to 63)."""
HOST_VALID = ("valid: a host name, an IPv4 or an IPv6 address, without a port (the FCI's "
              "ports are fixed), e.g. 172.16.0.2")


def number(low: float, high: float, low_open: bool = False) -> Callable[[str], float]:
    """An argparse ``type``: a finite number in [low, high] ((low, high] if ``low_open``)."""
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        above = value > low if low_open else value >= low
        if not (math.isfinite(value) and above and value <= high):
            bound = f"> {low:g}" if low_open else f">= {low:g}"
            raise argparse.ArgumentTypeError(f"invalid value {text!r}; valid: a finite number "
                                             f"{bound} and <= {high:g}")
        return value

    parse.__name__ = "number"
    return parse


def host(text: str) -> str:
    """An argparse ``type``: the robot's (or hand's) address, a host name or an IP address
    (``is_host``); an address with a port, brackets or spaces is refused."""
    if not is_host(text):
        port = re.fullmatch(r"\[?(.+?)\]?:[0-9]+", text)
        hint = " (a port is not part of it)" if port and is_host(port.group(1)) else ""
        raise argparse.ArgumentTypeError(f"invalid address {text!r}{hint}; {HOST_VALID}")
    return text


def is_host(text: str) -> bool:
    """Whether ``text`` is an IPv4 address, an IPv6 address (a ``%zone`` allowed, no brackets)
    or a host name (dot-separated RFC 1123 labels, at most 253 characters, a trailing dot
    allowed; all-numeric labels only as an IPv4 address, so ``172.16.0`` is not one)."""
    try:
        ipaddress.ip_address(text)
        return True
    except ValueError:
        pass
    labels = text[:-1].split(".") if text.endswith(".") else text.split(".")
    if not text or len(text) > 253 or not all(_LABEL.fullmatch(label) for label in labels):
        return False
    return not all(label.isdigit() for label in labels)


def path(text: str) -> Path:
    """An argparse ``type``: a file or folder path, not empty."""
    if not text.strip() or "\0" in text:
        raise argparse.ArgumentTypeError(f"invalid path {text!r}; valid: a file or folder path")
    return Path(text)


def pose_name(text: str) -> str:
    """An argparse ``type``: a pose name (``poses.NAME``)."""
    from impact_franka.poses import check_name

    try:
        return check_name(text, "name")
    except InvalidArgumentError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def step(text: str) -> tuple[float, float, float]:
    """An argparse ``type``: ``DX,DY,DZ`` [m], each finite and within 0.1 m (a step)."""
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 3 or not all(abs(v) <= 0.1 for v in values):
        raise argparse.ArgumentTypeError(f"invalid step {text!r}; valid: DX,DY,DZ in metres, "
                                         "each within 0.1")
    return values  # type: ignore[return-value]


def check_args(args: argparse.Namespace) -> dict[str, Pose]:
    """What needs several flags or the files; the pick and place poses by flag (an ``X,Y,Z``
    pose's orientation None: the TCP's, known once connected). ``InvalidArgumentError``."""
    step_m, step_at = getattr(args, "step_m", None), getattr(args, "step_at_s", None)
    if step_at is not None and step_m is None:
        raise InvalidArgumentError("invalid --step-at-s without --step-m; valid: give --step-m "
                                   "DX,DY,DZ with it, or neither")
    if step_m is not None and step_at is not None and not step_at < args.seconds:
        raise InvalidArgumentError(f"invalid --step-at-s {step_at:g}; valid: 0 <= value < "
                                   f"--seconds ({args.seconds:g})")
    if args.command == "teach":
        from impact_franka.poses import check_writable

        check_writable(args.poses, args.name, args.replace)
    if getattr(args, "out", None) is not None:
        check_out(args.out)
    return _check_pick_place(args) if args.command == "pick-place" else {}


def _check_pick_place(args: argparse.Namespace) -> dict[str, Pose]:
    """The pick and place poses, and the points above them, in the workspace."""
    import numpy as np

    from impact_franka.poses import check_workspace, read_poses, resolve_pose

    if args.poses is not None:
        read_poses(args.poses)  # named or not, a damaged file is refused
    targets = {}
    for flag in ("pick", "place"):
        pose = resolve_pose(getattr(args, flag), args.poses, None, f"--{flag}")
        check_workspace(pose.pos_m + np.array([0.0, 0.0, args.lift_m]),
                        f"--{flag} raised by --lift-m {args.lift_m:g}")
        targets[flag] = pose
    return targets


def check_out(out: Path) -> None:
    """``--out`` is a new or empty directory that can be written: ``InvalidArgumentError``
    for a file, a directory that holds anything (an earlier run: never mixed or overwritten)
    or a place where the folder or a file in it cannot be created. Tried, not inferred from
    permission bits (root passes those everywhere, ``/proc`` included): the folder and a probe
    file are created, then removed, so a refused or failed command leaves nothing behind
    (write_outputs creates the folder again after the run)."""
    valid = "valid: a new or empty directory in a writable place"
    if out.exists():
        if not out.is_dir():
            raise InvalidArgumentError(f"invalid --out {out}: not a directory; {valid}")
        try:
            held = any(out.iterdir())
        except OSError as exc:
            raise InvalidArgumentError(f"invalid --out {out}: {exc.strerror}; {valid}") from None
        if held:
            raise InvalidArgumentError(f"invalid --out {out}: it already holds files (an earlier "
                                       f"run?); {valid}")
    try:
        try_writing(out)
    except OSError as exc:
        where = exc.filename or out
        raise InvalidArgumentError(f"invalid --out {out}: cannot create {where} "
                                   f"({exc.strerror or exc}); {valid}") from None
