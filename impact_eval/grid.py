"""The evaluation grid: parameter values parsed from the CLI and paired per-episode seeds.

Every ``(method, value, episode)`` cell gets its seed from :func:`episode_seed`, which does not
depend on the method, so all methods face exactly the same episode initial conditions at each
parameter value (a paired comparison).
"""

from __future__ import annotations

import math

import numpy as np

from impact_control.errors import InvalidArgumentError
from impact_envs.tasks.values import GRID_DECIMALS, plain_number

__all__ = ["GRID_DECIMALS", "MAX_GRID_POINTS", "episode_seed", "format_value", "parse_grid",
           "plain_number"]

MAX_GRID_POINTS = 10_000
"""Most values a grid may expand to (guards against typos such as a step of ``1e-9``)."""

_GRID_HELP = "expected 'start:stop:step' (e.g. 0.1:10:0.5) or a comma list (e.g. 0.2,1,5)"


def _parse_number(text: str, spec: str) -> float:
    """Parse one finite float from ``text`` or raise a one-line ``InvalidArgumentError``."""
    try:
        value = float(text)
    except ValueError:
        raise InvalidArgumentError(
            f"malformed grid {spec!r}: {text!r} is not a number; {_GRID_HELP}"
        ) from None
    if not math.isfinite(value):
        raise InvalidArgumentError(f"malformed grid {spec!r}: {text!r} is not finite; {_GRID_HELP}")
    return value


def _parse_range(spec: str) -> list[float]:
    """Expand ``start:stop:step``; ``stop`` is included when it lands on the grid (±1e-9 step)."""
    parts = spec.split(":")
    if len(parts) != 3:
        raise InvalidArgumentError(f"malformed grid {spec!r}: {_GRID_HELP}")
    start, stop, step = (_parse_number(p.strip(), spec) for p in parts)
    if step <= 0:
        raise InvalidArgumentError(f"malformed grid {spec!r}: step must be > 0; {_GRID_HELP}")
    if stop < start:
        raise InvalidArgumentError(f"malformed grid {spec!r}: stop < start; {_GRID_HELP}")
    n_steps = math.floor((stop - start) / step + 1e-9)
    if n_steps + 1 > MAX_GRID_POINTS:
        raise InvalidArgumentError(
            f"malformed grid {spec!r}: expands to {n_steps + 1} values (max {MAX_GRID_POINTS})"
        )
    return [round(start + i * step, GRID_DECIMALS) for i in range(n_steps + 1)]


def parse_grid(spec: str) -> list[float]:
    """Parse a grid given as ``start:stop:step`` or a comma-separated list of numbers.

    Args:
        spec: e.g. ``"0.1:10:0.5"`` (0.1, 0.6, …, 9.6) or ``"0.2,1,5"``.

    Returns:
        The values in the order given (ranges ascending), rounded to ``GRID_DECIMALS``.

    Raises:
        InvalidArgumentError: empty, non-numeric, non-finite, zero/negative step, reversed range,
            duplicate values, or too many points. The message is one line.
    """
    spec = spec.strip()
    if not spec:
        raise InvalidArgumentError(f"malformed grid {spec!r}: empty; {_GRID_HELP}")
    if ":" in spec:
        if "," in spec:
            raise InvalidArgumentError(f"malformed grid {spec!r}: mixes ':' and ','; {_GRID_HELP}")
        values = _parse_range(spec)
    else:
        items = [s.strip() for s in spec.split(",")]
        if any(not s for s in items):
            raise InvalidArgumentError(f"malformed grid {spec!r}: empty list item; {_GRID_HELP}")
        values = [round(_parse_number(s, spec), GRID_DECIMALS) for s in items]
    if len(set(values)) != len(values):
        raise InvalidArgumentError(f"malformed grid {spec!r}: duplicate values")
    return values



def format_value(value: float) -> str:
    """Canonical text of a grid value, used as the CSV cell and the resume key (``repr``)."""
    return repr(round(float(value), GRID_DECIMALS))


def episode_seed(base_seed: int, value_index: int, episode: int) -> int:
    """Seed of one episode, shared by every method (paired comparison).

    The seed is a hash of ``(base_seed, value_index, episode)`` through NumPy's ``SeedSequence``,
    so nearby cells get statistically independent streams. Result in ``[0, 2**31)``.
    """
    if base_seed < 0 or value_index < 0 or episode < 0:
        raise InvalidArgumentError("seed, value index and episode index must be >= 0")
    state = np.random.SeedSequence([base_seed, value_index, episode]).generate_state(1)
    return int(state[0] >> 1)
