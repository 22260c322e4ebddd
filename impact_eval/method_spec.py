"""A method's specification: which policy, on which controller, preset, robot and
observation, and what ``run.json`` records of it (``MethodSpec``). Methods are named and
composed in ``methods.py``."""

from __future__ import annotations

from dataclasses import asdict, dataclass

from impact_control.errors import CheckpointError, InvalidArgumentError
from impact_control.presets import PRESETS
from impact_envs.envs.options import ObservationOptions, RobotOptions
from impact_envs.versions import robot_realism
from impact_eval.checkpoints import (
    checkpoint_demo_preset,
    checkpoint_observation,
    policy_checkpoint,
)
from impact_eval.method_parts import PolicyFactory

WARM_CONTROLLER = "impact"
"""The controller whose internal model ``warm`` warms up (``warm.py``); on another it would do
nothing."""


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
    policy: str | None = None
    """The canonical policy component (``method_parts.POLICY_FORMS``, e.g. ``dp.vanilla``) of a
    composed or shortcut method; None for an SB3 zip or a plugin's own factory."""
    demo_impedance: bool = False
    """Run the impedance section of the preset the checkpoint's demos were recorded under
    (``impedance_preset``: gains, null space, frame), every other section from ``preset``
    (IMPACT's stages, and also its target filter and torque-rate limiter, which are not the
    impedance; docs/eval.md, "The demos' impedance")."""

    def __post_init__(self) -> None:
        if self.carry and self.warm:
            raise InvalidArgumentError(
                f"method {self.name!r}: carry and warm exclude each other (a carried chain "
                "already starts each episode from the internal model the previous one left); "
                "choose one")
        if self.demo_impedance and not (self.policy or "").startswith("dp."):
            raise InvalidArgumentError(
                f"method {self.name!r}: demo_impedance reads the preset a diffusion-policy "
                "checkpoint's demos were recorded under; valid: a dp.<variant> policy")
        if self.warm and self.controller != WARM_CONTROLLER:
            raise InvalidArgumentError(
                f"method {self.name!r}: warm warms IMPACT's internal model, which the "
                f"{self.controller} controller does not have; valid: warm on the "
                f"{WARM_CONTROLLER} controller (POLICY+{WARM_CONTROLLER}[@PRESET]+warm)")

    def observation_for(self, env_id: str) -> ObservationOptions | None:
        """What the env observes for this method on ``env_id``: ``observation`` where set,
        else, for a diffusion-policy checkpoint, the cameras it was trained on
        (``checkpoints.checkpoint_observation``), else None (the state).

        Raises:
            CheckpointError: the method's checkpoint for ``env_id`` is missing or unreadable.
        """
        if self.observation is not None or self.policy is None \
                or not self.policy.startswith("dp."):
            return self.observation
        return checkpoint_observation(policy_checkpoint(env_id, self.policy))

    def impedance_preset(self, env_id: str) -> str | None:
        """With ``demo_impedance``, the preset whose impedance section runs on ``env_id``: the
        one the checkpoint's demos were recorded under; else None (``preset``'s own).

        Raises:
            CheckpointError: the checkpoint is missing, or its ``meta.json`` names no preset.
        """
        if not self.demo_impedance:
            return None
        path = policy_checkpoint(env_id, self.policy)
        preset = None if path is None else checkpoint_demo_preset(path)
        if preset not in PRESETS:
            what = ("records no demo controller preset" if preset is None
                    else f"records demo controller preset {preset!r}, not a preset here")
            raise CheckpointError(
                f"method {self.name!r}: checkpoint {path} {what} (meta.json "
                f"dataset.attrs.controller_preset); valid: one of {', '.join(PRESETS)}, or the "
                "method without +demo_impedance")
        return preset

    def env_key(self, env_id: str) -> tuple[str, str, str | None, ObservationOptions | None,
                                            RobotOptions | None, str | None]:
        """(controller, preset, action mode, observation, robot, impedance preset) on
        ``env_id``: methods with equal keys can share envs."""
        return (self.controller, self.preset, self.action_mode, self.observation_for(env_id),
                self.robot, self.impedance_preset(env_id))

    def settings_for(self, env_id: str) -> dict[str, object]:
        """What ``run.json`` and ``identity.json`` record per method (``args.method_controllers``)
        and ``--resume`` compares on ``env_id``: controller, preset, warm; ``carry``, ``robot``
        and ``impedance_preset`` (``demo_impedance``) only where set, so that the records of
        runs made before they existed still match. The robot is recorded as it runs there: an
        unset ``realism`` as the env version's profile (``impact_envs/versions.py``)."""
        out: dict[str, object] = {"controller": self.controller, "preset": self.preset,
                                  "warm": self.warm}
        if self.carry:
            out["carry"] = True
        if self.demo_impedance:
            out["impedance_preset"] = self.impedance_preset(env_id)
        if self.robot is not None:
            out["robot"] = asdict(self.robot.with_default_realism(robot_realism(env_id)))
        return out
