"""Method registry: a method is a policy on a controller with a preset, plus flags.

A method is written ``POLICY+CONTROLLER[@PRESET][+FLAG...]`` (``compose``): POLICY one of
``method_parts.POLICY_FORMS``, CONTROLLER one of ``CONTROLLERS``, PRESET one of ``PRESETS``
(default ``default``), FLAG among ``method_parts.FLAGS``. E.g. ``dp.vanilla+impact@paper`` is
``impact_paper``. The names below are shortcuts for compositions (``SHORTCUTS``); a composed
name gives the same rows as its shortcut, but for the ``method`` column.

| method            | composition                                   |
|-------------------|-----------------------------------------------|
| `scripted`        | `scripted+impedance`                          |
| `scripted_impact` | `scripted+impact`                             |
| `scripted_closed_loop` | `scripted.closed_loop+impedance`         |
| `vanilla_dp`      | `dp.vanilla+impedance`                        |
| `augmented_dp`    | `dp.augmented+impedance`                      |
| `vanilla_dp_authors` | `dp.vanilla_authors+impedance@authors_sim` (2) |
| `augmented_dp_authors` | `dp.augmented_authors+impedance@authors_sim` (2) |
| `impact`          | `dp.nominal+impact` (`<env>/impact`, else `<env>/vanilla`) |
| `impact_vanilla`  | `dp.vanilla+impact`                           |
| `impact_paper`    | `dp.vanilla+impact@paper`                     |
| `impact_warm`     | `dp.nominal+impact+warm`                      |
| `vanilla_dp_rgb`  | `dp.vanilla_rgb+impedance` (3)                |
| `augmented_dp_rgb` | `dp.augmented_rgb+impedance` (3)             |
| `impact_rgb`      | `dp.vanilla_rgb+impact` (3)                   |
| `impact_authors_rgb` | `dp.vanilla_rgb+impact@authors_sim+carry+commanded` (1, 3) |
| `impact_rgb_paper` | `dp.vanilla_rgb+impact@paper`                |
| `scripted_impact_paper` | `scripted+impact@paper`                 |
| `impact_authors`  | `dp.vanilla+impact@authors_sim+carry+commanded` (1) |
| `scripted_impact_authors` | `scripted+impact@authors_sim+carry+commanded` (1) |
| `lerobot_dp`      | `lerobot.lerobot_dp+impedance` (needs lerobot) |
| `lerobot_dp_impact` | `lerobot.lerobot_dp+impact`                 |
| `sb3:<path.zip>`  | any SB3 algorithm's policy, deterministic (``sb3.py``), `impact` |
| `sb3_impedance:<path.zip>` | the same, `impedance`                |

(1) The authors' simulation as they ran it: preset ``authors_sim``, the applied command read as
the joint torque (``commanded``: ``RobotOptions(torque_reading="commanded")``), and the
controller state carried across the episodes of a cell (``carry``: ``MethodSpec.carry``,
``chain.py``).
(2) Their baselines as they made them (HammerBasket, issue 55): DPs trained on their
demonstrator's demos (``impact-collect --expert authors``) with their action convention (xyz
deltas from the measured TCP), on their baselines' controller (impedance, preset
``authors_sim``).

(3) Visuomotor: the checkpoint sees its cameras and the robot's own state, never the object's
pose; the env renders the cameras its demonstrations recorded (``MethodSpec.observation_for``).
On HammerBasket the checkpoints learned from the authors' demonstrator under their baselines'
controller, so their table runs the baselines as ``dp.vanilla_rgb+impedance@authors_sim``
(docs/hammer_basket.md, "Policies with cameras").

Syntax: ``+`` and ``@`` appear in no shortcut, a ``sb3:`` prefix is tested first (its path
keeps any ``+`` or ``@``), and no ``,`` or ``:`` is used, so ``--method a,b`` and
``module:env`` ids parse as before.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import asdict

from impact_control.controller import CONTROLLERS
from impact_control.errors import InvalidArgumentError, check_choice
from impact_control.presets import PRESETS
from impact_envs.envs.options import RobotOptions, apply_robot_overrides
from impact_eval.checkpoints import (
    CHECKPOINTS_ENV_VAR,
    checkpoint_dir,
    env_short_name,
)
from impact_eval.method_parts import AUTHORS_ROBOT, FLAGS, policy_part
from impact_eval.method_spec import MethodSpec
from impact_eval.sb3 import load_sb3, sb3_action_mode

__all__ = ["CHECKPOINTS_ENV_VAR", "SHORTCUTS", "MethodSpec", "check_overrides_keep_flags",
           "checkpoint_dir", "compose",
           "env_short_name", "method_choices", "register_method", "resolve_method",
           "temporary_method"]

SB3_PREFIXES = {"sb3:": "impact", "sb3_impedance:": "impedance"}
"""Method-name prefixes of a Stable-Baselines3 zip and the controller each runs under."""


_REGISTRY: dict[str, MethodSpec] = {}


def register_method(spec: MethodSpec) -> None:
    """Add (or replace) a method; used by the built-ins below and by plugins/tests."""
    if spec.controller not in CONTROLLERS:
        raise InvalidArgumentError(
            f"invalid controller {spec.controller!r}; valid choices: {', '.join(CONTROLLERS)}"
        )
    check_choice("controller preset", spec.preset, PRESETS)
    _REGISTRY[spec.name] = spec


@contextlib.contextmanager
def temporary_method(spec: MethodSpec) -> Iterator[None]:
    """Register ``spec`` for the block only (``evaluate``'s policy object); its name must be
    new, so a built-in or plugin method is never shadowed and nothing outlives the call."""
    if spec.name in _REGISTRY or any(spec.name.startswith(p) for p in SB3_PREFIXES):
        raise InvalidArgumentError(
            f"method name {spec.name!r} is taken (built-in or registered methods: "
            f"{', '.join(_REGISTRY)}); choose another name")
    register_method(spec)
    try:
        yield
    finally:
        _REGISTRY.pop(spec.name, None)


def method_choices() -> list[str]:
    """Valid method names: the registered ones, the composition pattern and the SB3 ones."""
    return [*_REGISTRY, "POLICY+CONTROLLER[@PRESET][+FLAG...]",
            *(f"{p}<path.zip>" for p in SB3_PREFIXES)]


def compose(composition: str, name: str | None = None,
            description: str | None = None) -> MethodSpec:
    """The method ``POLICY+CONTROLLER[@PRESET][+FLAG...]`` (module docstring), named ``name``
    (default: the composition itself).

    Raises:
        InvalidArgumentError: a part is not among its choices, a flag repeats, or ``warm``
            meets ``carry`` (one line naming the valid choices).
    """
    policy_text, _, rest = composition.partition("+")
    control, *flags = rest.split("+") if rest else [""]
    controller, at, preset = control.partition("@")
    preset = preset if at else "default"  # "impact@" names no preset: refused below
    try:
        part = policy_part(policy_text)
        check_choice("controller", controller, CONTROLLERS)
        check_choice("preset", preset, PRESETS)
        for flag in flags:
            check_choice("flag", flag, FLAGS)
    except InvalidArgumentError as exc:
        raise InvalidArgumentError(
            f"method {composition!r} (POLICY+CONTROLLER[@PRESET][+FLAG...]): {exc}") from None
    if len(set(flags)) != len(flags):
        raise InvalidArgumentError(f"method {composition!r}: a flag repeats; give each once")
    return MethodSpec(
        name or composition, controller, part.build,
        description or f"{part.name} + {controller} controller, preset {preset}",
        preset=preset, warm="warm" in flags, observation=part.observation,
        robot=AUTHORS_ROBOT if "commanded" in flags else None, carry="carry" in flags,
        policy=part.name, demo_impedance="demo_impedance" in flags)


def resolve_method(name: str) -> MethodSpec:
    """Look a method up: ``sb3:<path>`` and compositions (a ``+`` in the name) are built on
    the fly, anything else is a registered name."""
    for prefix, controller in SB3_PREFIXES.items():
        if name.startswith(prefix) and len(name) > len(prefix):
            path = name[len(prefix):]
            return MethodSpec(name, controller, lambda _id, env, p=path: load_sb3(p, env),
                              f"SB3 policy, {controller} control",
                              action_mode=sb3_action_mode(path))
    if "+" in name:
        return compose(name)
    if name not in _REGISTRY:
        raise InvalidArgumentError(
            f"unknown method {name!r}; valid choices: {', '.join(method_choices())}"
        )
    return _REGISTRY[name]


def check_overrides_keep_flags(spec: MethodSpec, robot_overrides: tuple[str, ...]) -> None:
    """One line if a ``--robot-set`` item changes a robot field ``spec`` fixes (its
    ``+commanded`` flag: ``torque_reading='commanded'``), naming both: the rows would be
    another method's under this one's name. An item that sets the same value, or another
    field (``realism=fr3``), passes; ``carry`` and ``warm`` are no robot or controller field,
    so no override can undo them, and ``--controller-set`` changes the preset by design."""
    if spec.robot is None or not robot_overrides:
        return
    default = RobotOptions()
    fixed = {f: v for f, v in asdict(spec.robot).items() if v != getattr(default, f)}
    robot = apply_robot_overrides(spec.robot, robot_overrides)  # what would run
    for field, value in fixed.items():
        if getattr(robot, field) == value:
            continue
        item = [i for i in robot_overrides if i.partition("=")[0].strip() == field][-1]
        flag = "+commanded" if getattr(AUTHORS_ROBOT, field) == value else "robot setting"
        raise InvalidArgumentError(
            f"--robot-set {item!r} contradicts method {spec.name!r}'s {flag} "
            f"({field}={value!r}); valid: drop the override, or a method without {flag}")


SHORTCUTS = (
    ("scripted", "scripted+impedance", "scripted expert, impedance control"),
    ("scripted_impact", "scripted+impact", "scripted expert, IMPACT control"),
    ("scripted_closed_loop", "scripted.closed_loop+impedance",
     "scripted expert compensating the sag in closed loop (the Augmented demonstrator), "
     "impedance control"),
    ("vanilla_dp", "dp.vanilla+impedance", "Vanilla DP, impedance"),
    ("augmented_dp", "dp.augmented+impedance", "Augmented DP, impedance"),
    ("vanilla_dp_authors", "dp.vanilla_authors+impedance@authors_sim",
     "Vanilla DP on the authors' demonstrator's demos and action convention, on their "
     "baselines' impedance (HammerBasket)"),
    ("augmented_dp_authors", "dp.augmented_authors+impedance@authors_sim",
     "Augmented DP (0.1-10 kg) on the authors' demonstrator's demos and action convention, "
     "on their baselines' impedance (HammerBasket)"),
    ("impact", "dp.nominal+impact",
     "nominal-mass DP (impact checkpoint, else vanilla) + IMPACT controller"),
    ("impact_vanilla", "dp.vanilla+impact",
     "Vanilla DP + IMPACT controller (the vanilla checkpoint even where an impact checkpoint "
     "ships)"),
    ("scripted_impact_paper", "scripted+impact@paper",
     "scripted expert, IMPACT control, paper preset"),
    ("impact_paper", "dp.vanilla+impact@paper", "Vanilla DP + IMPACT controller, paper preset"),
    ("impact_warm", "dp.nominal+impact+warm",
     "Vanilla DP + IMPACT controller, internal model warmed up on the cell"),
    ("impact_authors", "dp.vanilla+impact@authors_sim+carry+commanded",
     "Vanilla DP + the authors' IMPACT controller as their simulation runs it (preset "
     "authors_sim, commanded torque reading, state carried across a cell's episodes)"),
    ("scripted_impact_authors", "scripted+impact@authors_sim+carry+commanded",
     "scripted expert + the authors' IMPACT controller as their simulation runs it"),
    ("lerobot_dp", "lerobot.lerobot_dp+impedance",
     "LeRobot's Diffusion Policy (trained by lerobot-train on our export), impedance"),
    ("lerobot_dp_impact", "lerobot.lerobot_dp+impact",
     "LeRobot's Diffusion Policy + IMPACT controller"),
    ("vanilla_dp_rgb", "dp.vanilla_rgb+impedance",
     "visuomotor Vanilla DP (cameras + the robot's own state), impedance"),
    ("augmented_dp_rgb", "dp.augmented_rgb+impedance",
     "visuomotor Augmented DP (cameras + the robot's own state), impedance"),
    ("impact_rgb", "dp.vanilla_rgb+impact", "visuomotor Vanilla DP + IMPACT controller"),
    ("impact_authors_rgb", "dp.vanilla_rgb+impact@authors_sim+carry+commanded",
     "visuomotor Vanilla DP + the authors' IMPACT controller as their simulation runs it"),
    ("impact_rgb_paper", "dp.vanilla_rgb+impact@paper",
     "visuomotor Vanilla DP + IMPACT controller, paper preset"),
)
"""(shortcut name, composition, description) of every built-in method."""

for _name, _composition, _description in SHORTCUTS:
    register_method(compose(_composition, _name, _description))


