"""What a sweep is, declared once: ``SweepSpec`` (everything that defines its rows) and
``RunOptions`` (where and how it runs, which never changes a row).

The CLI (``SweepSpec.from_cli``) and ``evaluate()`` build the same spec; ``prepare`` checks it
against the env, the workers get it inside ``SweepConfig``, ``run.json`` records it as
``"spec"`` (``to_json``) and the manifest reruns it from its arguments (``to_argv``). Every
check that needs no env is made here, when the spec is built, in one line naming the valid
choices.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import asdict, dataclass
from pathlib import Path

from impact_control.config import ControllerConfig, beyond_hardware_limits
from impact_control.errors import InvalidArgumentError
from impact_control.overrides import apply_overrides
from impact_envs.envs.options import apply_robot_overrides
from impact_envs.parallel import check_executor
from impact_envs.tasks.bins import MassBin, check_bins, format_bins, parse_bins
from impact_eval.grid import format_value, parse_grid

SPEC_FORMAT = 1
"""Version of ``SweepSpec.to_json``'s layout (run.json ``"spec_format"``)."""


def _at_least(name: str, value: int, low: int) -> None:
    """One line unless ``value`` is an int >= ``low``."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise InvalidArgumentError(f"{name} must be an integer, got {value!r}")
    if value < low:
        raise InvalidArgumentError(f"{name} must be >= {low}, got {value}")


def parse_method_list(text: str) -> tuple[str, ...]:
    """``--method a,b`` -> names (an empty or repeated item is bad input)."""
    names = tuple(m.strip() for m in text.split(","))
    if any(not n for n in names):
        raise InvalidArgumentError(f"malformed --method {text!r}: empty item")
    if len(set(names)) != len(names):
        raise InvalidArgumentError(f"malformed --method {text!r}: repeated method")
    return names


def values_from_text(grid: str | None, mass_bins: str | None
                     ) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """(values, bin upper edges) of a grid text (``grid.parse_grid``; no edges) or of a
    ``--mass-bins`` text (the bins' lower edges, and their upper edges); exactly one given."""
    if (grid is None) == (mass_bins is None):
        raise InvalidArgumentError(
            "give either a grid (--masses/--param-values) or --mass-bins (exactly one)")
    if grid is not None:
        return tuple(parse_grid(grid)), ()
    bins = parse_bins(mass_bins or "")
    return tuple(b.lo for b in bins), tuple(b.hi for b in bins)


@dataclass(frozen=True)
class SweepSpec:
    """A sweep's rows: which env, methods, parameter values (or mass bins), episodes, seed and
    controller / robot changes. Two runs with equal specs write the same rows."""

    env_id: str
    """As given (``IMPACT/Hammer-v1``; ``module:ID`` imports the module that registers it)."""
    methods: tuple[str, ...]
    """Method names as given (shortcuts, compositions or ``sb3:<zip>``; ``methods.py``)."""
    values: tuple[float, ...]
    """Grid values, rounded to ``GRID_DECIMALS``, in the order given; with ``bin_highs`` the
    bins' lower edges."""
    bin_highs: tuple[float, ...] = ()
    """Mass bins ``[values[i], bin_highs[i])`` (``bins.py``); empty: a grid of fixed values."""
    param: str | None = None
    """The swept parameter (None: the env's first)."""
    episodes: int = 20
    """Episodes per (method, value) cell."""
    seed: int = 0
    """Base seed of the paired episode seeds (``grid.episode_seed``)."""
    controller_overrides: tuple[str, ...] = ()
    """``SECTION.FIELD=VALUE`` changes of each method's controller preset (``--controller-set``)."""
    robot_overrides: tuple[str, ...] = ()
    """``FIELD=VALUE`` changes of every method's simulated robot (``--robot-set``)."""
    beyond_hardware_limits: bool = False
    """Allow controller overrides above the FR3's torque and torque-rate limits."""

    def __post_init__(self) -> None:
        for name in ("methods", "controller_overrides", "robot_overrides"):  # lists too
            object.__setattr__(self, name, tuple(getattr(self, name)))
        for name in ("values", "bin_highs"):
            object.__setattr__(self, name, tuple(float(v) for v in getattr(self, name)))
        if not isinstance(self.env_id, str) or not self.env_id:
            raise InvalidArgumentError(f"invalid env id {self.env_id!r}; valid: a registered "
                                       "env id, e.g. IMPACT/Hammer-v1")
        parse_method_list(",".join(self.methods))  # empty or repeated names
        _at_least("--episodes", self.episodes, 1)
        _at_least("--seed", self.seed, 0)
        self._check_values()
        if self.controller_overrides:  # bad overrides fail here, before any env is built
            overridden = apply_overrides(ControllerConfig(), self.controller_overrides)
            above = beyond_hardware_limits(overridden.limits)
            if above and not self.beyond_hardware_limits:
                raise InvalidArgumentError(
                    f"{'; '.join(above)}: above the FR3's hardware limits (87 Nm x4, 12 Nm x3, "
                    "1000 Nm/s); pass --beyond-hardware-limits to run it anyway (run.json "
                    "records it)")
        if self.robot_overrides:  # bad robot fields fail here too, in one line
            apply_robot_overrides(None, self.robot_overrides).resolved_realism()

    def _check_values(self) -> None:
        if not self.values:
            raise InvalidArgumentError("no parameter values; give at least one (or one bin)")
        if any(not math.isfinite(v) for v in self.values + self.bin_highs):
            raise InvalidArgumentError(f"values {self.values!r} must be finite numbers")
        if self.bin_highs:
            if len(self.bin_highs) != len(self.values):
                raise InvalidArgumentError(
                    f"{len(self.values)} bin lower edges but {len(self.bin_highs)} upper ones")
            check_bins(self.bins)  # reversed, out of order, overlapping
        elif len(set(self.values)) != len(self.values):
            raise InvalidArgumentError(f"duplicate values in {list(self.values)}")

    @property
    def bins(self) -> tuple[MassBin, ...]:
        """The mass bins (empty for a grid)."""
        return tuple(MassBin(lo, hi) for lo, hi in zip(self.values, self.bin_highs, strict=True))

    @classmethod
    def from_cli(cls, a: argparse.Namespace) -> SweepSpec:
        """The spec of a parsed ``impact-eval`` command line (``sweep_command.sweep_parser``):
        the method list, and the grid text (``--masses`` / ``--param-values``) or the
        ``--mass-bins`` text, parsed."""
        values, highs = values_from_text(a.grid, a.mass_bins)
        return cls(env_id=a.env, methods=parse_method_list(a.method), values=values,
                   bin_highs=highs, param=a.param, episodes=a.episodes, seed=a.seed,
                   controller_overrides=tuple(a.controller_set),
                   robot_overrides=tuple(a.robot_set),
                   beyond_hardware_limits=a.beyond_hardware_limits)


    def to_json(self) -> dict[str, object]:
        """The spec as run.json's ``"spec"`` (lists for tuples; ``from_json`` reads it back)."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}

    @classmethod
    def from_json(cls, data: dict) -> SweepSpec:
        """The spec ``to_json`` wrote (a damaged one is one line)."""
        try:
            return cls(**data)
        except (TypeError, ValueError) as exc:
            raise InvalidArgumentError(f"damaged sweep spec ({exc}); restore run.json") from None

    def to_argv(self) -> list[str]:
        """The ``impact-eval`` arguments that define these rows (no output or run options)."""
        values = (["--mass-bins", format_bins(self.bins)] if self.bin_highs
                  else ["--param-values", ",".join(format_value(v) for v in self.values)])
        argv = ["--env", self.env_id, "--method", ",".join(self.methods), *values,
                "--episodes", str(self.episodes), "--seed", str(self.seed)]
        if self.param:
            argv += ["--param", self.param]
        for override in self.controller_overrides:
            argv += ["--controller-set", override]
        for override in self.robot_overrides:
            argv += ["--robot-set", override]
        if self.beyond_hardware_limits:
            argv.append("--beyond-hardware-limits")
        return argv


@dataclass(frozen=True)
class RunOptions:
    """Where and how a sweep runs; none of it changes a row."""

    out: Path
    """Output directory (``episodes.csv``, ``run.json``, ``summary.csv``, ``plots/``)."""
    workers: int = 1
    """Worker processes (``--workers``)."""
    envs_per_worker: int = 20
    """Envs each worker steps in lockstep with one batched policy call."""
    resume: bool = False
    """Continue ``out`` with the same spec (``--resume``)."""
    extend: bool = False
    """Continue ``out`` adding methods or values (``--extend``)."""
    video_episodes: int = 0
    """The first this many episodes of every cell as MP4 (``--video``; ``out/videos``)."""
    executor: str = "local"
    """``local`` or ``ray`` (``--executor``)."""
    ray_address: str | None = None
    """The Ray cluster to join (``--ray-address``; ``ray`` only)."""
    allow_code_change: bool = False
    """Resume even if other code wrote the earlier rows (``--allow-code-change``;
    ``code_check.py``)."""

    def __post_init__(self) -> None:
        _at_least("--workers", self.workers, 1)
        _at_least("--envs-per-worker", self.envs_per_worker, 1)
        _at_least("--video", self.video_episodes, 0)
        check_executor(self.executor, self.ray_address)
