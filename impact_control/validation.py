"""Validation helpers of the controller configs (one-line ``InvalidArgumentError``s)."""

from __future__ import annotations

import math

from impact_control.errors import InvalidArgumentError

FRAMES: tuple[str, ...] = ("world", "tcp")
"""Frames a stage may work in: the world (= robot base) frame, or the TCP frame (the
authors' controller, ``use_local_jacobian``)."""


def check_positive(name: str, values: float | tuple[float, ...], allow_zero: bool = False) -> None:
    """Raise ``InvalidArgumentError`` unless every value is finite and > 0 (or >= 0)."""
    seq = values if isinstance(values, tuple) else (values,)
    for v in seq:
        ok = math.isfinite(v) and (v >= 0.0 if allow_zero else v > 0.0)
        if not ok:
            bound = ">= 0" if allow_zero else "> 0"
            raise InvalidArgumentError(f"invalid {name} {values!r}; valid: finite values {bound}")


def check_len(name: str, values: tuple[float, ...], n: int) -> None:
    if len(values) != n:
        raise InvalidArgumentError(f"invalid {name} {values!r}; valid: a tuple of {n} floats")


def check_optional_positive(name: str, value: float | None) -> None:
    """Raise ``InvalidArgumentError`` unless ``value`` is None or finite and > 0."""
    if value is not None:
        check_positive(name, value)


def checked_gripper_command(gripper_cmd: float) -> float:
    """``gripper_cmd`` as a float in [-1, 1] (-1 open ... +1 closed), else a one-line
    ``InvalidArgumentError``."""
    try:
        value = float(gripper_cmd)
    except (TypeError, ValueError):
        value = math.nan
    if not -1.0 <= value <= 1.0:
        raise InvalidArgumentError(f"invalid gripper_cmd {gripper_cmd!r}; valid: a number "
                                   "in [-1, 1] (-1 open ... +1 closed)")
    return value
