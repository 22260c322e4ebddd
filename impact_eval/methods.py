"""Method registry: method name -> (policy factory, low-level controller).

Factories import their dependencies on use, so the registry can be listed (and the sweep
machinery tested) without the scripted experts, diffusion policies or Stable-Baselines3.

| method            | policy                                   | controller  |
|-------------------|------------------------------------------|-------------|
| `scripted`        | scripted expert                          | `impedance` |
| `scripted_impact` | scripted expert                          | `impact`    |
| `scripted_closed_loop` | scripted expert, closed-loop sag compensation | `impedance` |
| `vanilla_dp`      | DP checkpoint `<env>/vanilla`            | `impedance` |
| `augmented_dp`    | DP checkpoint `<env>/augmented`          | `impedance` |
| `impact`          | DP checkpoint `<env>/impact`, else `<env>/vanilla` | `impact` |
| `impact_vanilla`  | DP checkpoint `<env>/vanilla`            | `impact`    |
| `impact_paper`    | DP checkpoint `<env>/vanilla`            | `impact`, preset `paper` |
| `impact_warm`     | as `impact`, warm internal model         | `impact`    |
| `vanilla_dp_rgb`  | visuomotor DP checkpoint `<env>/vanilla_rgb`, cameras only | `impedance` |
| `impact_rgb`      | the same checkpoint                      | `impact`    |
| `impact_rgb_paper` | the same checkpoint                     | `impact`, preset `paper` |
| `scripted_impact_paper` | scripted expert                    | `impact`, preset `paper` |
| `impact_authors`  | DP checkpoint `<env>/vanilla`    | `impact`, `authors_sim`, carried (1) |
| `scripted_impact_authors` | scripted expert          | `impact`, `authors_sim`, carried (1) |
| `lerobot_dp`      | LeRobot DP checkpoint `<env>/lerobot_dp` (needs lerobot) | `impedance` |
| `lerobot_dp_impact` | the same checkpoint                    | `impact`    |
| `sb3:<path.zip>`  | any SB3 algorithm's policy, deterministic (``sb3.py``) | `impact` |
| `sb3_impedance:<path.zip>` | the same | `impedance` |

(1) The authors' simulation as they ran it: preset ``authors_sim``, the applied command read as
the joint torque (``RobotOptions(torque_reading="commanded")``), and the controller state
carried across the episodes of a cell (``MethodSpec.carry``, ``chain.py``).
"""

from __future__ import annotations

import contextlib
import os
import re
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass
from pathlib import Path

import gymnasium as gym

from impact_control.controller import CONTROLLERS
from impact_control.errors import CheckpointError, InvalidArgumentError, check_choice
from impact_control.policy import Policy
from impact_control.presets import PRESETS
from impact_envs.envs.options import ObservationOptions, RobotOptions
from impact_eval.sb3 import load_sb3, sb3_action_mode

"""Values of the env's ``controller`` kwarg."""

CHECKPOINTS_ENV_VAR = "IMPACT_CHECKPOINTS"
"""Environment variable overriding the shipped checkpoint root ``impact_envs/checkpoints``."""

SB3_PREFIXES = {"sb3:": "impact", "sb3_impedance:": "impedance"}
"""Method-name prefixes of a Stable-Baselines3 zip and the controller each runs under."""

PolicyFactory = Callable[[str, gym.Env], Policy]
"""``factory(env_id, env) -> Policy``; ``env`` is a built env of this method's controller."""


@dataclass(frozen=True)
class MethodSpec:
    """How to evaluate one method: which policy, on which controller."""

    name: str
    controller: str
    build: PolicyFactory
    description: str
    preset: str = "default"
    """Controller preset of the method's env (``impact_control.presets.PRESETS``)."""
    warm: bool = False
    """Score episodes from an internal model already trained by one unscored warm-up episode
    of the same cell ("warm robot", the paper's Phase B; docs/eval.md)."""
    action_mode: str | None = None
    """``impact_envs.wrappers.RLActions`` mode the policy acts in (None: the env's own)."""
    observation: ObservationOptions | None = None
    """What the env observes (``gym.make(..., observation=...)``); None: the state."""
    robot: RobotOptions | None = None
    """The simulated robot (``gym.make(..., robot=...)``, e.g. its torque reading); None: the
    env's default."""
    carry: bool = False
    """Run each (method, value) cell as one chain of episodes on one env, each episode
    starting with the controller state the previous one left (the authors' benchmark, their
    controller activated once per bin; ``chain.py``, docs/eval.md "Carried controller
    state"). Excludes ``warm``."""

    def __post_init__(self) -> None:
        if self.carry and self.warm:
            raise InvalidArgumentError(
                f"method {self.name!r}: carry and warm exclude each other (a carried chain "
                "already starts each episode from the internal model the previous one left); "
                "choose one")

    @property
    def env_key(self) -> tuple[str, str, str | None, ObservationOptions | None,
                               RobotOptions | None]:
        """(controller, preset, action mode, observation, robot): methods with equal keys can
        share envs."""
        return self.controller, self.preset, self.action_mode, self.observation, self.robot

    @property
    def settings(self) -> dict[str, object]:
        """What ``run.json`` and ``identity.json`` record per method (``args.method_controllers``)
        and ``--resume`` compares: controller, preset, warm; ``carry`` and ``robot`` only where
        set, so that the records of runs made before they existed still match."""
        out: dict[str, object] = {"controller": self.controller, "preset": self.preset,
                                  "warm": self.warm}
        if self.carry:
            out["carry"] = True
        if self.robot is not None:
            out["robot"] = asdict(self.robot)
        return out


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
    """Valid method names, including the ``sb3:<path.zip>`` pattern."""
    return [*_REGISTRY, *(f"{p}<path.zip>" for p in SB3_PREFIXES)]


def resolve_method(name: str) -> MethodSpec:
    """Look a method up; ``sb3:<path>`` builds a spec on the fly."""
    for prefix, controller in SB3_PREFIXES.items():
        if name.startswith(prefix) and len(name) > len(prefix):
            path = name[len(prefix):]
            return MethodSpec(name, controller, lambda _id, env, p=path: load_sb3(p, env),
                              f"SB3 policy, {controller} control",
                              action_mode=sb3_action_mode(path))
    if name not in _REGISTRY:
        raise InvalidArgumentError(
            f"unknown method {name!r}; valid choices: {', '.join(method_choices())}"
        )
    return _REGISTRY[name]


def env_short_name(env_id: str) -> str:
    """``"IMPACT/Hammer-v0"`` (or ``"mod:IMPACT/Hammer-v0"``) -> ``"hammer"``."""
    name = env_id.rsplit(":", 1)[-1].rsplit("/", 1)[-1]
    return re.sub(r"-v\d+$", "", name).lower()


def checkpoint_dir(env_id: str, variant: str) -> Path:
    """Directory of the shipped ``variant`` ("vanilla" | "augmented") DP checkpoint of an env.

    The root is ``$IMPACT_CHECKPOINTS`` if set, else ``impact_envs/checkpoints``.

    Raises:
        CheckpointError: the directory does not exist (one-line message).
    """
    root = os.environ.get(CHECKPOINTS_ENV_VAR)
    if root is None:
        import impact_envs

        root = str(Path(impact_envs.__file__).parent / "checkpoints")
    path = Path(root) / env_short_name(env_id) / variant
    if not path.is_dir():
        raise CheckpointError(
            f"no {variant} checkpoint for {env_id}: {path} does not exist "
            f"(train one with impact-train or set ${CHECKPOINTS_ENV_VAR})"
        )
    return path


def _scripted_factory(compensation: str) -> PolicyFactory:
    """Factory of the env's scripted expert with the given ``compensation`` mode."""

    def build(env_id: str, env: gym.Env) -> Policy:
        try:
            from impact_envs.policies.experts import make_expert
        except ImportError as exc:
            raise InvalidArgumentError(f"no scripted experts available: {exc}") from None
        return make_expert(env_id, compensation=compensation)

    return build


_build_scripted = _scripted_factory("none")
"""Scripted expert without load compensation (the controller's job)."""


def _dp_factory(variant: str) -> PolicyFactory:
    """Factory loading the ``variant`` diffusion-policy checkpoint of the env."""

    def build(env_id: str, env: gym.Env) -> Policy:
        path = checkpoint_dir(env_id, variant)
        try:
            from impact_envs.policies.diffusion.policy import DiffusionPolicy

            policy = DiffusionPolicy.load(path)
        except Exception as exc:  # noqa: BLE001 - any load failure means a corrupt checkpoint
            msg = " ".join(str(exc).split())[:160]
            raise CheckpointError(
                f"cannot load {variant} checkpoint {path}: {type(exc).__name__}: {msg}"
            ) from None
        from impact_envs.policies.diffusion.compat import check_policy_env

        check_policy_env(policy, env_id, env, str(path))
        return policy

    return build


def _lerobot_factory(variant: str) -> PolicyFactory:
    """Factory loading the env's ``variant`` LeRobot checkpoint (``lerobot-train``'s
    ``pretrained_model``) behind our protocol; a one-line CheckpointError without LeRobot."""

    def build(env_id: str, env: gym.Env) -> Policy:  # noqa: ARG001 - the factory signature
        from impact_lerobot.policy import load_lerobot_policy

        return load_lerobot_policy(checkpoint_dir(env_id, variant), env_id)

    return build


def _build_impact_dp(env_id: str, env: gym.Env) -> Policy:
    """The env's ``impact`` checkpoint (demos recorded under the IMPACT controller at the
    nominal mass) where one ships, else its ``vanilla`` checkpoint."""
    try:
        checkpoint_dir(env_id, "impact")
    except CheckpointError:
        return _dp_factory("vanilla")(env_id, env)
    return _dp_factory("impact")(env_id, env)


RGB_OBSERVATION = ObservationOptions(obs_mode="rgb", cameras=("overview", "wrist"),
                                     image_width=96, image_height=96, shadows=False)
"""Observation of the ``*_rgb`` methods: the two cameras the shipped visuomotor checkpoint was
trained on, 96 x 96, without shadows (docs/diffusion_policy.md, "Visuomotor policy")."""

AUTHORS_ROBOT = RobotOptions(torque_reading="commanded")
"""The robot of the ``*_authors`` methods: the controller reads the applied command as the joint
torque, as the authors' simulation does (``qfrc_actuator``, noise-free)."""


for _spec in (
    MethodSpec("scripted", "impedance", _build_scripted, "scripted expert, impedance control"),
    MethodSpec("scripted_impact", "impact", _build_scripted, "scripted expert, IMPACT control"),
    MethodSpec("scripted_closed_loop", "impedance", _scripted_factory("closed_loop"),
               "scripted expert compensating the sag in closed loop (the Augmented "
               "demonstrator), impedance control"),
    MethodSpec("vanilla_dp", "impedance", _dp_factory("vanilla"), "Vanilla DP, impedance"),
    MethodSpec("augmented_dp", "impedance", _dp_factory("augmented"), "Augmented DP, impedance"),
    MethodSpec("impact", "impact", _build_impact_dp,
               "nominal-mass DP (impact checkpoint, else vanilla) + IMPACT controller"),
    MethodSpec("impact_vanilla", "impact", _dp_factory("vanilla"),
               "Vanilla DP + IMPACT controller (the vanilla checkpoint even where an impact "
               "checkpoint ships)"),
    MethodSpec("scripted_impact_paper", "impact", _build_scripted,
               "scripted expert, IMPACT control, paper preset", preset="paper"),
    MethodSpec("impact_paper", "impact", _dp_factory("vanilla"),
               "Vanilla DP + IMPACT controller, paper preset", preset="paper"),
    MethodSpec("impact_warm", "impact", _build_impact_dp,
               "Vanilla DP + IMPACT controller, internal model warmed up on the cell", warm=True),
    MethodSpec("impact_authors", "impact", _dp_factory("vanilla"),
               "Vanilla DP + the authors' IMPACT controller as their simulation runs it (preset "
               "authors_sim, commanded torque reading, state carried across a cell's episodes)",
               preset="authors_sim", robot=AUTHORS_ROBOT, carry=True),
    MethodSpec("scripted_impact_authors", "impact", _build_scripted,
               "scripted expert + the authors' IMPACT controller as their simulation runs it",
               preset="authors_sim", robot=AUTHORS_ROBOT, carry=True),
    MethodSpec("lerobot_dp", "impedance", _lerobot_factory("lerobot_dp"),
               "LeRobot's Diffusion Policy (trained by lerobot-train on our export), impedance"),
    MethodSpec("lerobot_dp_impact", "impact", _lerobot_factory("lerobot_dp"),
               "LeRobot's Diffusion Policy + IMPACT controller"),
    MethodSpec("vanilla_dp_rgb", "impedance", _dp_factory("vanilla_rgb"),
               "visuomotor Vanilla DP (cameras + the robot's own state), impedance",
               observation=RGB_OBSERVATION),
    MethodSpec("impact_rgb", "impact", _dp_factory("vanilla_rgb"),
               "visuomotor Vanilla DP + IMPACT controller", observation=RGB_OBSERVATION),
    MethodSpec("impact_rgb_paper", "impact", _dp_factory("vanilla_rgb"),
               "visuomotor Vanilla DP + IMPACT controller, paper preset", preset="paper",
               observation=RGB_OBSERVATION),
):
    register_method(_spec)
