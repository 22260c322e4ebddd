"""Mass bins: ``--mass-bins 0.1-0.3,0.3-0.5,...`` instead of a grid of fixed masses.

A bin is ``[lo, hi)`` [kg]. Each episode of a bin cell draws its object mass uniformly in
the bin from the episode's own seed (``draw_in_bin``), so every method meets the same mass in
the same episode (paired, as the grid's seeds are), and ``episodes.csv`` records it in
``drawn_mass_kg``. A bin is keyed by its lower edge: ``param_value`` is ``lo`` and the row's
``param_name`` is ``<param>_bin`` (``bin_param_name``); run.json records every bin's upper edge.

A bin draws the env's mass (``mass_param_name``: the parameter its task declares ``is_mass``),
the one ``drawn_mass_kg`` records and the LeRobot plugin's ``mass_bin`` draws; a bin of
any other parameter (a push in N, a friction) is refused (``check_bin_param``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from impact_control.errors import InvalidArgumentError
from impact_envs.tasks.values import GRID_DECIMALS, plain_number

MASS_PARAM = "object_mass"
"""The mass of an env that declares no task parameter (a foreign env): what it reports as
``info["object_mass"]`` is recorded as ``drawn_mass_kg``. An IMPACT env's mass is the parameter
its task declares ``is_mass`` (``mass_param_name``), reported under its own name."""

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
    edges are fine). Messages quote the text as given, never a number printed back."""
    items = [s.strip() for s in spec.strip().split(",")]
    if not spec.strip() or any(not s for s in items):
        raise InvalidArgumentError(f"malformed --mass-bins {spec!r}: empty item; {_BINS_HELP}")
    bins: list[MassBin] = []
    for i, item in enumerate(items):
        parts = item.split("-")
        if len(parts) != 2:
            exponent = any(p.strip().lower().endswith("e") for p in parts[:-1])
            hint = " (write an edge with an exponent in fixed point, e.g. 0.00001)" * exponent
            raise InvalidArgumentError(
                f"malformed --mass-bins {spec!r}: {item!r} is not LO-HI{hint}; {_BINS_HELP}")
        lo, hi = (_edge(p.strip(), spec) for p in parts)
        if not lo < hi:
            raise InvalidArgumentError(
                f"malformed --mass-bins {spec!r}: {item!r} is reversed or empty (LO < HI); "
                f"{_BINS_HELP}")
        if bins and lo < bins[-1].hi:
            raise InvalidArgumentError(
                f"malformed --mass-bins {spec!r}: {item!r} overlaps or precedes "
                f"{items[i - 1]!r}; {_BINS_HELP}")
        bins.append(MassBin(lo, hi))
    return tuple(bins)


def check_bins(bins: tuple[MassBin, ...]) -> None:
    """One line unless every bin has ``lo < hi`` and follows the one before without overlap
    (bins given as numbers, e.g. a run.json's spec; ``parse_bins`` checks a text)."""
    for i, b in enumerate(bins):
        if not b.lo < b.hi:
            raise InvalidArgumentError(
                f"invalid mass bin [{b.lo!r}, {b.hi!r}): reversed or empty (LO < HI)")
        if i and b.lo < bins[i - 1].hi:
            raise InvalidArgumentError(
                f"invalid mass bin [{b.lo!r}, {b.hi!r}): overlaps or precedes "
                f"[{bins[i - 1].lo!r}, {bins[i - 1].hi!r}); valid: ascending, not overlapping")


def edge_text(value: float) -> str:
    """A bin edge as ``--mass-bins`` text that ``parse_bins`` reads back to the same number
    (``values.plain_number``: fixed point where the ``repr`` has an exponent, whose ``-`` would
    split the bin)."""
    return plain_number(value)


def format_bins(bins: tuple[MassBin, ...]) -> str:
    """The ``--mass-bins`` text of ``bins`` (``parse_bins`` reads it back)."""
    return ",".join(f"{edge_text(b.lo)}-{edge_text(b.hi)}" for b in bins)


def draw_in_bin(lo: float, hi: float, seed: int) -> float:
    """The episode's mass [kg], uniform in ``[lo, hi)``, a fixed function of its seed."""
    u = np.random.default_rng(np.random.SeedSequence([int(seed), DRAW_STREAM])).random()
    return min(lo + (hi - lo) * float(u), math.nextafter(hi, lo))


def bin_param_name(param_name: str) -> str:
    """The ``param_name`` of a bin sweep's rows (``object_mass`` -> ``object_mass_bin``)."""
    return f"{param_name}_bin"


def mass_param_name(params: Sequence[object]) -> str | None:
    """The parameter a mass bin draws (and the LeRobot plugin's ``object_mass`` and
    ``mass_bin`` set), among an env's declared ``TaskParam``s: the first declared ``is_mass``
    (``Task.mass_param``; Calligraphy: ``tool_mass``); ``object_mass`` for an env that
    declares no parameter; None where none is a mass."""
    if not params:
        return MASS_PARAM
    return next((str(p.name) for p in params if getattr(p, "is_mass", False)), None)


def check_bin_param(env_id: str, param_name: str, params: Sequence[object]) -> None:
    """One line unless ``param_name`` is the env's mass (``mass_param_name``): a bin draws a
    mass in kg, which ``episodes.csv`` records as ``drawn_mass_kg``, for ``impact-eval`` and
    the LeRobot plugin alike (docs/eval.md "Mass bins")."""
    mass = mass_param_name(params)
    if param_name == mass:
        return
    unit = next((str(getattr(p, "unit", "")) for p in params
                 if getattr(p, "name", None) == param_name), "")
    what = f"in {unit}" if unit else "without a unit"
    if unit == "kg":
        what += ", not the mass drawn_mass_kg records"
    if mass is None:
        raise InvalidArgumentError(
            f"--mass-bins draws a mass [kg], and {env_id} has no mass parameter ({param_name} "
            f"is {what}); valid: a grid of {param_name} (--param-values)")
    raise InvalidArgumentError(
        f"--mass-bins draws {env_id}'s mass {mass} [kg] (episodes.csv: drawn_mass_kg), not "
        f"{param_name} ({what}); valid: --param {mass} with --mass-bins, or a grid of "
        f"{param_name} (--param-values)")


def mass_info_key(env: object) -> str:
    """Where ``env``'s ``info`` (and its reset options) name its mass: the parameter its task
    declares ``is_mass`` (``Task.mass_param``), ``MASS_PARAM`` for an env without a task or
    without a mass. ``impact-eval`` records it as ``drawn_mass_kg``; ``impact-collect`` hands
    it to the expert."""
    task = getattr(getattr(env, "unwrapped", env), "task", None)
    params = tuple(getattr(task, "params", ()))
    return mass_param_name(params) or MASS_PARAM
