"""The parts a method is composed of (``POLICY+CONTROLLER[@PRESET][+FLAG...]``, ``methods.py``):
the policy component (how its policy is built, what it observes) and the flags.

| policy              | what it builds                                               |
|---------------------|--------------------------------------------------------------|
| `scripted`          | the env's scripted expert, no load compensation              |
| `scripted.closed_loop` | the expert compensating the sag in closed loop (Augmented) |
| `dp.<variant>`      | the diffusion-policy checkpoint `<env>/<variant>` (1)        |
| `dp.nominal`        | `<env>/impact` where one ships, else `<env>/vanilla`         |
| `lerobot.<variant>` | a LeRobot checkpoint `<env>/<variant>` (needs lerobot)       |

(1) Its observation is the one its checkpoint was trained on: the state, or the cameras and
image size its demonstrations recorded (``checkpoints.checkpoint_observation``).

Factories import their dependencies on use, so the registry can be listed (and the sweep
machinery tested) without the scripted experts, diffusion policies or LeRobot.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

import gymnasium as gym

from impact_control.errors import CheckpointError, InvalidArgumentError
from impact_control.policy import Policy
from impact_envs.envs.options import ObservationOptions, RobotOptions
from impact_eval.checkpoints import checkpoint_dir

PolicyFactory = Callable[[str, gym.Env], Policy]
"""``factory(env_id, env) -> Policy``; ``env`` is a built env of this method's controller."""

AUTHORS_ROBOT = RobotOptions(torque_reading="commanded")
"""The robot of the ``commanded`` flag (the ``*_authors`` methods): the controller reads the
applied command as the joint torque, as the authors' simulation does (``qfrc_actuator``,
noise-free)."""

FLAGS = ("warm", "carry", "commanded", "demo_impedance")
"""Flags of a composed method: ``warm`` (``MethodSpec.warm``), ``carry`` (``MethodSpec.carry``),
``commanded`` (the robot ``AUTHORS_ROBOT``), ``demo_impedance``
(``MethodSpec.demo_impedance``)."""

POLICY_FORMS = ("scripted", "scripted.closed_loop", "dp.<variant>", "dp.nominal",
                "lerobot.<variant>")
"""The policy component's forms, as error messages and the help name them."""

_VARIANT = re.compile(r"[a-z0-9_]+")


@dataclass(frozen=True)
class PolicyPart:
    """A method's policy: ``name`` (its canonical form, e.g. ``dp.vanilla``), ``build`` and
    the observation it needs (None: the state)."""

    name: str
    build: PolicyFactory
    observation: ObservationOptions | None = None


def _scripted_factory(compensation: str) -> PolicyFactory:
    """Factory of the env's scripted expert with the given ``compensation`` mode."""

    def build(env_id: str, env: gym.Env) -> Policy:  # noqa: ARG001 - the factory signature
        try:
            from impact_envs.policies.experts import make_expert
        except ImportError as exc:
            raise InvalidArgumentError(f"no scripted experts available: {exc}") from None
        return make_expert(env_id, compensation=compensation)

    return build


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


def _build_nominal_dp(env_id: str, env: gym.Env) -> Policy:
    """The env's ``impact`` checkpoint (demos recorded under the IMPACT controller at the
    nominal mass) where one ships, else its ``vanilla`` checkpoint."""
    try:
        checkpoint_dir(env_id, "impact")
    except CheckpointError:
        return _dp_factory("vanilla")(env_id, env)
    return _dp_factory("impact")(env_id, env)


def policy_part(text: str) -> PolicyPart:
    """The policy component ``text`` names (one of ``POLICY_FORMS``).

    Raises:
        InvalidArgumentError: another form, or a variant outside ``[a-z0-9_]`` (one line).
    """
    if text == "scripted":
        return PolicyPart(text, _scripted_factory("none"))
    if text == "scripted.closed_loop":
        return PolicyPart(text, _scripted_factory("closed_loop"))
    if text == "dp.nominal":
        return PolicyPart(text, _build_nominal_dp)
    kind, dot, variant = text.partition(".")
    if dot and _VARIANT.fullmatch(variant):
        if kind == "dp":  # what it observes is its checkpoint's (MethodSpec.observation_for)
            return PolicyPart(text, _dp_factory(variant))
        if kind == "lerobot":
            return PolicyPart(text, _lerobot_factory(variant))
    raise InvalidArgumentError(
        f"invalid policy {text!r}; valid choices: {', '.join(POLICY_FORMS)} (a variant is a "
        "checkpoint folder name of [a-z0-9_])")
