"""How a task parameter's value is rounded and written: one rule for the sweep's grids
(``impact_eval.grid``), the mass bins (``impact_envs.tasks.bins``) and their messages."""

from __future__ import annotations

GRID_DECIMALS = 10
"""Decimals a parameter value is rounded to, so that ``0.1 + 0.2`` and ``0.3`` are one grid
point, one bin edge and one resume key."""


def plain_number(value: float) -> str:
    """``value`` as a user types it, for messages and argument text: its ``repr``, or fixed
    point where that has an exponent (``0.00001``, not ``1e-05``)."""
    text = repr(float(value))
    if "e" not in text:
        return text
    return f"{value:.{GRID_DECIMALS}f}".rstrip("0").rstrip(".")
