"""Task side of an environment (dm_control style): randomization, observation, success.

A task declares itself: its env id, scene file, objects, varying physical parameters
(``TaskParam``: name, default, range, unit) and observation entries (``ObsEntry``); the env
builds its spaces and its ``reset(options=...)`` validation from that, and
``tasks/registry.py`` registers it. The robot side (``robot/sim.py``) knows bodies, sensors
and contacts; ``envs/base.py`` combines the two. Scripted experts are looked up by task name
(``policies/experts.py``). docs/adding_a_task.md walks through a new task.
"""

from __future__ import annotations

import numbers
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import mujoco
import numpy as np

from impact_control.errors import InvalidArgumentError
from impact_control.lie import rot6d_from_matrix
from impact_envs.robot.sim import FrankaSim


@dataclass(frozen=True)
class TaskParam:
    """A physical parameter a task varies (the evaluation sweep axis is the first one),
    declared once: every consumer (``impact-eval``, ``impact-collect``, the LeRobot plugin,
    ``episodes.csv``, ``info``) reads its name, range, unit and whether it is a mass from here.

    Attributes:
        name: key used in ``reset(options={name: value})``, env kwargs and ``info``.
        default: nominal value.
        low, high: valid range (inclusive).
        unit: unit string for plots and docs.
        is_mass: whether it is a mass [kg] a mass bin may draw; the task's first such
            parameter is its mass (``Task.mass_param``: ``info`` reports it under its own
            name, ``episodes.csv`` records it as ``drawn_mass_kg``).
    """

    name: str
    default: float
    low: float
    high: float
    unit: str
    is_mass: bool = False

    def __post_init__(self) -> None:
        if self.is_mass and self.unit != "kg":
            raise InvalidArgumentError(
                f"invalid TaskParam {self.name!r}: is_mass with unit {self.unit!r}; valid: "
                "unit 'kg' for a mass")

    def validate(self, value: float) -> float:
        """Return ``value`` as float, or raise a one-line error naming the valid range.

        Only real numbers count: a bool, a string or an array is refused (``True`` is not 1 kg).
        """
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Real, np.number)):
            raise InvalidArgumentError(
                f"{self.name} must be a real number, got {type(value).__name__} {value!r}")
        v = float(value)
        if not (np.isfinite(v) and self.low <= v <= self.high):
            raise InvalidArgumentError(
                f"{self.name}={value!r} out of range; valid: {self.low} to {self.high} {self.unit}"
            )
        return v


@dataclass(frozen=True)
class ObsEntry:
    """One flat float32 entry of the observation ``Dict`` (a Box of ``size`` values).

    Attributes:
        name: key in the observation.
        size: number of values.
        low, high: bounds of every value (observations are clipped to them).
        unit: unit string ("" for none).
        description: what it is, for docs and ``describe_observations``.
    """

    name: str
    size: int
    low: float
    high: float
    unit: str
    description: str


OBJECT_POSE = (
    ObsEntry("object_pos", 3, -2.0, 2.0, "m", "object centre of mass, world frame"),
    ObsEntry("object_rot6d", 6, -1.0, 1.0, "", "object orientation, rot6d"),
)
"""The observation entries of ``FreeBody.observe``."""


class BodyMass:
    """Sets a body's mass from its nominal value, scaling rotational inertia by the same ratio.

    Always derived from the nominal (never compounded); call :func:`refresh_constants` after.
    """

    def __init__(self, model: mujoco.MjModel, body: str) -> None:
        self.id = model.body(body).id
        self.nominal_mass = float(model.body_mass[self.id])
        self.nominal_inertia = model.body_inertia[self.id].copy()

    def set(self, model: mujoco.MjModel, mass_kg: float) -> None:
        """Write mass [kg] and inertia [kg m^2] (COM fixed: uniform density scaling)."""
        model.body_mass[self.id] = mass_kg
        model.body_inertia[self.id] = self.nominal_inertia * (mass_kg / self.nominal_mass)


class FreeBody:
    """A task object on a free joint: ids looked up once, resting placement, pose observation."""

    def __init__(self, model: mujoco.MjModel, body: str, joint: str) -> None:
        self.id = model.body(body).id
        jid = model.joint(joint).id
        self.qpos_adr = int(model.jnt_qposadr[jid])
        self.dof_adr = int(model.jnt_dofadr[jid])

    def place(self, data: mujoco.MjData, xy: np.ndarray, z_m: float, yaw_rad: float) -> None:
        """Put the body frame at (x, y, z) [m], turned by ``yaw_rad`` about world z, at rest."""
        a = self.qpos_adr
        data.qpos[a:a + 3] = [xy[0], xy[1], z_m]
        data.qpos[a + 3:a + 7] = [np.cos(yaw_rad / 2), 0.0, 0.0, np.sin(yaw_rad / 2)]
        data.qvel[self.dof_adr:self.dof_adr + 6] = 0.0

    def observe(self, data: mujoco.MjData) -> dict[str, np.ndarray]:
        """``object_pos`` (centre of mass, world [m]) and ``object_rot6d`` of the body."""
        return {"object_pos": data.xipos[self.id].copy(),
                "object_rot6d": rot6d_from_matrix(data.xmat[self.id].reshape(3, 3))}


def refresh_constants(sim: FrankaSim) -> None:
    """Recompute derived constants after a model change (``mj_setConst`` resets qpos)."""
    mujoco.mj_setConst(sim.model, sim.data)
    mujoco.mj_resetData(sim.model, sim.data)


class Task(ABC):
    """Base class of IMPACT tasks."""

    name: str
    scene_xml: str
    object_bodies: tuple[str, ...]
    params: tuple[TaskParam, ...]
    max_episode_steps: int
    workspace_low: np.ndarray
    workspace_high: np.ndarray
    env_id: ClassVar[str]
    """Gymnasium id under which ``tasks/registry.py`` registers the task's env."""
    observations: ClassVar[tuple[ObsEntry, ...]]
    """The task's observation entries (after the robot's,
    ``envs/observation_space.ROBOT_OBSERVATIONS``); ``observation()`` returns exactly these
    keys."""
    privileged_observations: ClassVar[tuple[str, ...] | None] = None
    """Names of the task entries that a camera and the robot's own sensors cannot give
    (object poses, goals shown in the scene): the image observation modes leave them out
    (``envs/pixels.py``). None: every task entry."""
    env_entry_point: ClassVar[str | None] = None
    """"module:Class" of an ``ImpactEnv`` subclass documenting this task; None registers the
    generic ``ImpactEnv`` with this task."""
    success_ends_episode: ClassVar[bool] = True
    """False for a task whose success is judged at the end of the episode only (the env then
    never terminates it early, whatever ``terminate_on_success`` says): HammerBasket, whose
    protocol runs every episode for its full 60 s."""
    hand: ClassVar[str] = "franka_hand"
    """The hand whose grasp-force range and default apply (``robot/hand.HANDS``) unless
    ``RobotOptions(hand=...)`` names another."""
    has_tick_hook: ClassVar[bool] = False
    """Declared capability: True when the task overrides ``before_tick`` (the closed loop then
    calls it before every 1 kHz tick). Checked when the subclass is defined."""

    def __init_subclass__(cls, **kwargs: object) -> None:
        super().__init_subclass__(**kwargs)
        overrides = cls.before_tick is not Task.before_tick
        if overrides != cls.has_tick_hook:
            raise TypeError(f"{cls.__name__}: set has_tick_hook = {overrides} (it "
                            f"{'overrides' if overrides else 'does not override'} before_tick)")

    @property
    def param_name(self) -> str:
        """The sweep axis (first parameter)."""
        return self.params[0].name

    @classmethod
    def mass_param(cls) -> TaskParam | None:
        """The task's mass: its first parameter declared ``is_mass`` (None: it has none)."""
        return next((p for p in cls.params if p.is_mass), None)

    def param(self, name: str) -> TaskParam:
        """The parameter called ``name`` or a one-line error naming the valid ones."""
        for p in self.params:
            if p.name == name:
                return p
        valid = ", ".join(p.name for p in self.params)
        raise InvalidArgumentError(f"unknown parameter {name!r} for {self.name}; valid: {valid}")

    @abstractmethod
    def bind(self, sim: FrankaSim) -> None:
        """Look up ids and nominal values in the compiled scene (called once)."""

    @abstractmethod
    def apply_params(self, sim: FrankaSim, values: dict[str, float]) -> None:
        """Write physical parameters into the model (before the state is placed)."""

    @abstractmethod
    def initialize_episode(self, sim: FrankaSim, rng: np.random.Generator) -> np.ndarray:
        """Randomize and place objects; return the initial arm configuration [rad]."""

    @abstractmethod
    def observation(self, sim: FrankaSim) -> dict[str, np.ndarray]:
        """Task part of the observation: one array per entry of ``observations``."""

    @abstractmethod
    def is_success(self, sim: FrankaSim) -> bool:
        """Whether the task is accomplished in the current state."""

    def before_tick(self, sim: FrankaSim, time_s: float) -> None:  # noqa: B027
        """Hook run before every 1 kHz tick (e.g. external disturbances) when the task
        declares ``has_tick_hook = True``. Default: nothing."""

    def control_inputs(
        self, sim: FrankaSim, action: np.ndarray
    ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """Per policy step: explicit commanded wrench and internal-model learning mask.

        Returns ``(wrench_cmd_world, learn_mask)``: an explicit wrench the robot should apply
        to the environment (robot-on-environment sign, [N, Nm], e.g. a desired pressing force
        for hybrid force control) and 6 bools (False freezes internal-model learning on that
        axis). Default: ``(None, None)`` (pure pose tracking, learning on every axis).
        """
        return None, None

    def info(self, sim: FrankaSim) -> dict[str, float | bool]:
        """Extra task-specific per-step info. Default: none."""
        return {}

    def outcome_settled(self, sim: FrankaSim) -> bool:
        """True when this episode's outcome can no longer change from the scene's state alone
        (``impact-eval --end-early`` ends it once this holds for ``rollout.SETTLE_S``).
        Default: never (every episode runs to its end)."""
        return False

    def supported_weight_n(self, values: Mapping[str, float]) -> float:
        """Object-on-scene contact force [N] that is the task's normal support, not a safety
        event, for the episode's parameter ``values``: the weight of an object the task sets
        down. The evaluation subtracts it from the object's contact force with the scene
        (``impact_eval.safety.scene_contact``); the robot's own contact with the scene counts
        in full. Default: 0 (every contact force counts)."""
        return 0.0

    def dense_reward(self, sim: FrankaSim) -> float:
        """Shaped reward in [0, 1] for ``reward_type="dense"`` (1 on success); each task
        documents its stages. Default: the sparse success indicator."""
        return float(self.is_success(sim))


def pick_place_reward(tcp: np.ndarray, obj: np.ndarray, goal: np.ndarray, grasped: bool,
                      lift_m: float, success: bool) -> float:
    """Staged shaping of a pick-and-place (Gymnasium-Robotics / robosuite style), in [0, 1]:
    reach 0.25 (1 - tanh(10 |tcp - obj|)), grasp +0.25, lift +0.1 (object raised 2 cm above
    where it rested), place +0.4 (1 - tanh(5 |obj - goal|), while grasped or once near the
    goal), 1.0 on success. All distances [m], world frame."""
    if success:
        return 1.0
    reach = 0.25 * (1.0 - np.tanh(10.0 * np.linalg.norm(tcp - obj)))
    place_err = float(np.linalg.norm(obj - goal))
    place = 0.4 * (1.0 - np.tanh(5.0 * place_err)) if grasped or place_err < 0.05 else 0.0
    return float(reach + 0.25 * grasped + 0.1 * (grasped and lift_m > 0.02) + place)
