"""What an env's state snapshot (``state.py``) and its carried controller (``carry.py``) read
and write of an ``ImpactEnv``: its parts, declared here so that neither module imports
``envs/base.py``, which imports both."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from impact_control.controller import ImpactController
from impact_envs.robot.sim import FrankaSim
from impact_envs.tasks.base import Task


class ArmModelState(Protocol):
    """The controller's arm model, as far as a snapshot needs it."""

    def state_arrays(self) -> dict[str, np.ndarray]: ...


class EnvParts(Protocol):
    """An ``ImpactEnv`` (envs/base.py) as its state and carry see it."""

    sim: FrankaSim
    dynamics: ArmModelState
    controller: ImpactController
    task: Task
    np_random: np.random.Generator
    controller_mode: str
    controller_preset: str
