"""Validation helpers of the controller configs (one-line ``InvalidArgumentError``s)."""

from __future__ import annotations

import math

from impact_envs.errors import InvalidArgumentError


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
