"""What a sweep is, declared once: ``SweepSpec`` (everything that defines its rows) and
``RunOptions`` (where and how it runs, which never changes a row).

The CLI (``SweepSpec.from_cli``) and ``evaluate()`` build the same spec; ``prepare`` checks it
against the env, the workers get it inside ``SweepConfig``, identity.json and run.json record
it once (``RunIdentity.to_json``; earlier layouts: ``run_migration``) and the manifest reruns it
from its arguments (``to_argv``). Each field's command-line form is declared with the field
(``cli_options``). Every
check that needs no env is made here, when the spec is built, in one line naming the valid
choices.
"""

from __future__ import annotations

import argparse
import math
import os
from dataclasses import asdict, dataclass
from pathlib import Path

from impact_control.config import ControllerConfig, beyond_hardware_limits
from impact_control.errors import InvalidArgumentError
from impact_control.overrides import apply_overrides
from impact_envs.cli import robot_set_help
from impact_envs.envs.options import apply_robot_overrides
from impact_envs.parallel import check_executor
from impact_envs.tasks.bins import MassBin, check_bins, format_bins, parse_bins
from impact_eval.cli_options import (
    Repeated,
    Switch,
    Value,
    add_arguments,
    from_namespace,
    option,
    to_argv,
)
from impact_eval.grid import format_value, parse_grid


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


def _method_help() -> str:
    """``--method``'s help: every registered method (the registry, imported only when a
    parser is built)."""
    from impact_eval.methods import method_choices

    return "comma list of: " + ", ".join(method_choices())


_CONTROLLER_SET_HELP = (
    "change one field of the controller config on top of each method's preset (its @PRESET, "
    "docs/eval.md 'Methods'; repeatable; ablations), e.g. "
    "internal_model.slow_rate_max=1.5; recorded in run.json")


@dataclass(frozen=True)
class SweepSpec:
    """A sweep's rows: which env, methods, parameter values (or mass bins), episodes, seed and
    controller / robot changes. Two runs with equal specs write the same rows.

    Each field declares its command-line form once (``cli_options.option``): the parser,
    ``from_cli``, ``to_argv`` and ``--resume``'s check are generated from it. The values and
    bins are one composite option (``add_grid_arguments``)."""

    env_id: str = option(Value("--env", "env id, e.g. IMPACT/Hammer-v2"))
    """As given (``IMPACT/Hammer-v1``; ``module:ID`` imports the module that registers it)."""
    methods: tuple[str, ...] = option(
        Value("--method", _method_help, parse=parse_method_list, show=",".join), resume="grow")
    """Method names as given (shortcuts, compositions or ``sb3:<zip>``; ``methods.py``)."""
    values: tuple[float, ...] = option(None, resume="grow")
    """Grid values, rounded to ``GRID_DECIMALS``, in the order given; with ``bin_highs`` the
    bins' lower edges (``--masses`` / ``--param-values`` / ``--mass-bins``)."""
    bin_highs: tuple[float, ...] = option(None, default=(), resume="grow")
    """Mass bins ``[values[i], bin_highs[i])`` (``bins.py``); empty: a grid of fixed values."""
    episodes: int = option(Value("--episodes", "episodes per (method, value) (default 20)",
                                 type=int), default=20)
    """Episodes per (method, value) cell."""
    seed: int = option(Value("--seed", "base seed of the paired episode seeds", type=int,
                             cli_default=0), default=0)
    """Base seed of the paired episode seeds (``grid.episode_seed``)."""
    param: str | None = option(Value(
        "--param", "parameter to sweep: any the env declares (default: its first, e.g. "
        "object_mass)"), default=None, resume="free")
    """The swept parameter (None: the env's first). ``--resume`` compares it resolved
    (``RunIdentity.param_name``)."""
    controller_overrides: tuple[str, ...] = option(
        Repeated("--controller-set", _CONTROLLER_SET_HELP, metavar="SECTION.FIELD=VALUE"),
        default=())
    """``SECTION.FIELD=VALUE`` changes of each method's controller preset (``--controller-set``)."""
    robot_overrides: tuple[str, ...] = option(
        Repeated("--robot-set", robot_set_help("run.json, checked on --resume; for every "
                                               "method"), metavar="FIELD=VALUE"), default=())
    """``FIELD=VALUE`` changes of every method's simulated robot (``--robot-set``)."""
    end_early: bool = option(Switch(
        "--end-early", "end an episode once its outcome can no longer change (the env's "
        "outcome_settled for 2 s; HammerBasket); its length and the columns summed or peaked "
        "over it then cover the steps it ran (docs/eval.md)"), default=False)
    """End each episode once its env reports a settled outcome for ``rollout.SETTLE_S``
    (``ImpactEnv.outcome_settled``): fewer steps, the same outcomes (checked against
    full-length episodes, docs/eval.md "Ending an episode early")."""
    beyond_hardware_limits: bool = option(Switch(
        "--beyond-hardware-limits", "allow --controller-set limits above the FR3's (87/12 Nm, "
        "1000 Nm/s); recorded in run.json"), default=False, resume="free")
    """Allow controller overrides above the FR3's torque and torque-rate limits (it changes no
    row: an override above them is refused without it)."""

    def __post_init__(self) -> None:
        for name in ("methods", "controller_overrides", "robot_overrides"):  # lists too
            object.__setattr__(self, name, tuple(getattr(self, name)))
        for name in ("values", "bin_highs"):
            object.__setattr__(self, name, tuple(float(v) for v in getattr(self, name)))
        if not isinstance(self.env_id, str) or not self.env_id:
            raise InvalidArgumentError(f"invalid env id {self.env_id!r}; valid: a registered "
                                       "env id, e.g. IMPACT/Hammer-v2")
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
        """The spec of a parsed ``impact-eval`` command line (``add_arguments``): each
        declared option parsed by its declaration, and the grid text (``--masses`` /
        ``--param-values``) or the ``--mass-bins`` text."""
        values, highs = values_from_text(a.grid, a.mass_bins)
        return cls(**from_namespace(cls, a), values=values, bin_highs=highs)

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
        """The ``impact-eval`` arguments that define these rows (no output or run options):
        the declared options in declaration order, the grid after ``--method``."""
        grid = (["--mass-bins", format_bins(self.bins)] if self.bin_highs
                else ["--param-values", ",".join(format_value(v) for v in self.values)])
        argv = to_argv(self)
        at = argv.index("--method") + 2
        return [*argv[:at], *grid, *argv[at:]]

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        """The spec's options on ``parser``: the declared ones and the grid."""
        add_grid_arguments(parser)
        add_arguments(parser, cls)


def add_grid_arguments(parser: argparse.ArgumentParser) -> None:
    """The values (or bins) of a sweep: one of ``--masses`` / ``--param-values`` (a grid) or
    ``--mass-bins`` (``SweepSpec.values`` and ``bin_highs``; ``values_from_text``)."""
    grid = parser.add_mutually_exclusive_group()
    grid.add_argument(
        "--masses", dest="grid", metavar="GRID",
        help="values of the env's parameter (alias of --param-values): start:stop:step (stop "
        "included when on the grid) or a comma list")
    grid.add_argument("--param-values", dest="grid", metavar="GRID", help="same as --masses")
    grid.add_argument(
        "--mass-bins", metavar="BINS",
        help="bins [LO, HI) in kg of the env's mass instead of fixed values, e.g. "
        "0.1-0.3,0.3-0.5,0.5-1: each episode draws its mass uniformly in its bin from its "
        "seed (episodes.csv: drawn_mass_kg; param_value is the bin's LO). The mass is "
        "object_mass (Calligraphy: tool_mass; Disturbance, whose first parameter is a push: "
        "give --param object_mass); any other parameter is refused: sweep it as a grid")


@dataclass(frozen=True)
class RunOptions:
    """Where and how a sweep runs; none of it changes a row. Each field declares its
    command-line form once (``cli_options.option``), as ``SweepSpec``'s do."""

    out: Path = option(Value("--out", "output directory", type=Path))
    """Output directory (``episodes.csv``, ``run.json``, ``summary.csv``, ``plots/``)."""
    workers: int = option(Value(
        "--workers", "worker processes (default: CPU count; 1 runs in-process); --executor "
        "local only", type=int, cli_default=os.cpu_count() or 1), default=1)
    """Worker processes (``--workers``; the command line's default is the CPU count)."""
    envs_per_worker: int = option(Value(
        "--envs-per-worker", "envs each worker steps in lockstep with one batched policy call "
        "(default 20)", type=int), default=20)
    """Envs each worker steps in lockstep with one batched policy call."""
    resume: bool = option(Switch(
        "--resume", "continue OUT with the same methods, grid and episodes: skip (method, "
        "value, episode) rows already written"), default=False)
    """Continue ``out`` with the same spec (``--resume``)."""
    extend: bool = option(Switch(
        "--extend", "continue OUT adding methods or grid values (every earlier one kept, same "
        "--episodes): each new cell gets the same episode count"), default=False)
    """Continue ``out`` adding methods or values (``--extend``)."""
    video_episodes: int = option(Value(
        "--video", "write the first K episodes of every cell as MP4 to OUT/videos "
        "(imageio-ffmpeg; rendering is checked before anything is written; no display: "
        "MUJOCO_GL=egl is picked when unset)", type=int, metavar="K"), default=0)
    """The first this many episodes of every cell as MP4 (``--video``; ``out/videos``)."""
    executor: str = option(Value(
        "--executor", "local (worker processes on this machine) | ray (Ray tasks on a "
        "cluster, local or remote: docs/scale.md; needs pip install -e '.[ray]')"),
        default="local")
    """``local`` or ``ray`` (``--executor``)."""
    ray_address: str | None = option(Value(
        "--ray-address", "Ray cluster to join, e.g. 10.0.0.1:6379 (default: $RAY_ADDRESS, else "
        "a new local Ray instance)", metavar="ADDR"), default=None)
    """The Ray cluster to join (``--ray-address``; ``ray`` only)."""
    allow_code_change: bool = option(Switch(
        "--allow-code-change", "with --resume/--extend: continue even if another commit or "
        "other uncommitted changes wrote the earlier rows (recorded in run.json)"),
        default=False)
    """Resume even if other code wrote the earlier rows (``--allow-code-change``;
    ``code_check.py``)."""

    @classmethod
    def from_cli(cls, a: argparse.Namespace) -> RunOptions:
        """The run options of a parsed command line (``add_arguments``)."""
        return cls(**from_namespace(cls, a))

    @classmethod
    def add_arguments(cls, parser: argparse.ArgumentParser) -> None:
        """The run options on ``parser``."""
        add_arguments(parser, cls)

    def __post_init__(self) -> None:
        _at_least("--workers", self.workers, 1)
        _at_least("--envs-per-worker", self.envs_per_worker, 1)
        _at_least("--video", self.video_episodes, 0)
        check_executor(self.executor, self.ray_address)
