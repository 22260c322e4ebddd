"""Mass bins: ``--mass-bins 0.1-0.3,0.3-0.5,...`` instead of a grid of fixed masses.

A bin is ``[lo, hi)`` [kg]. Each episode of a bin cell draws its object mass uniformly in
the bin from the episode's own seed (``draw_in_bin``), so every method meets the same mass in
the same episode (paired, as the grid's seeds are), and ``episodes.csv`` records it in
``drawn_mass_kg``. A bin is keyed by its lower edge: ``param_value`` is ``lo`` and the row's
``param_name`` is ``<param>_bin`` (``bin_param_name``); run.json records every bin's upper edge.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from impact_control.errors import InvalidArgumentError
from impact_eval.grid import GRID_DECIMALS

_BINS_HELP = ("expected a comma list of LO-HI bins in kg, ascending and not overlapping "
              "(e.g. 0.1-0.3,0.3-0.5,0.5-1)")

DRAW_STREAM = 0x6D617373
"""Second word of the ``SeedSequence`` a bin's mass is drawn from (``b"mass"``): a stream of
its own, apart from the env's and the policy's streams of the same episode seed."""


@dataclass(frozen=True)
class MassBin:
    """One bin ``[lo, hi)`` [kg]."""

    lo: float
    hi: float

    @property
    def label(self) -> str:
        """``"0.1–0.3"``: how tables and plots name it."""
        return f"{self.lo:g}–{self.hi:g}"


def _edge(text: str, spec: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InvalidArgumentError(
            f"malformed --mass-bins {spec!r}: {text!r} is not a number; {_BINS_HELP}") from None
    if not math.isfinite(value):
        raise InvalidArgumentError(
            f"malformed --mass-bins {spec!r}: {text!r} is not finite; {_BINS_HELP}")
    return round(value, GRID_DECIMALS)


def parse_bins(spec: str) -> tuple[MassBin, ...]:
    """``"0.1-0.3,0.3-0.5"`` -> bins; a one-line ``InvalidArgumentError`` if it is empty,
    malformed, reversed (``lo >= hi``), out of order or overlapping (``[lo, hi)``: touching
    edges are fine)."""
    items = [s.strip() for s in spec.strip().split(",")]
    if not spec.strip() or any(not s for s in items):
        raise InvalidArgumentError(f"malformed --mass-bins {spec!r}: empty item; {_BINS_HELP}")
    bins = []
    for item in items:
        parts = item.split("-")
        if len(parts) != 2:
            raise InvalidArgumentError(
                f"malformed --mass-bins {spec!r}: {item!r} is not LO-HI; {_BINS_HELP}")
        lo, hi = (_edge(p.strip(), spec) for p in parts)
        if not lo < hi:
            raise InvalidArgumentError(
                f"malformed --mass-bins {spec!r}: {item!r} is reversed or empty (LO < HI); "
                f"{_BINS_HELP}")
        if bins and lo < bins[-1].hi:
            raise InvalidArgumentError(
                f"malformed --mass-bins {spec!r}: {item!r} overlaps or precedes "
                f"{bins[-1].label}; {_BINS_HELP}")
        bins.append(MassBin(lo, hi))
    return tuple(bins)


def format_bins(bins: tuple[MassBin, ...]) -> str:
    """The ``--mass-bins`` text of ``bins`` (``parse_bins`` reads it back)."""
    return ",".join(f"{b.lo!r}-{b.hi!r}" for b in bins)


def draw_in_bin(lo: float, hi: float, seed: int) -> float:
    """The episode's mass [kg], uniform in ``[lo, hi)``, a fixed function of its seed."""
    u = np.random.default_rng(np.random.SeedSequence([int(seed), DRAW_STREAM])).random()
    return min(lo + (hi - lo) * float(u), math.nextafter(hi, lo))


def bin_param_name(param_name: str) -> str:
    """The ``param_name`` of a bin sweep's rows (``object_mass`` -> ``object_mass_bin``)."""
    return f"{param_name}_bin"
