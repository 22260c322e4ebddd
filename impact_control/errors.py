"""Exception hierarchy: every error raised on purpose by IMPACT derives from ``ImpactError``."""

from __future__ import annotations


class ImpactError(Exception):
    """Base class of all IMPACT errors."""


class InvalidArgumentError(ImpactError, ValueError):
    """A user-supplied value is out of range or not one of the valid choices.

    The message is one line and names the valid choices.
    """


class CheckpointError(ImpactError):
    """A checkpoint is missing, corrupt or does not match the expected config."""


class SimulationError(ImpactError):
    """The simulation diverged (non-finite state) or violated a hard invariant."""


def check_choice(name: str, value: object, choices: list[str] | tuple[str, ...]) -> None:
    """Raise ``InvalidArgumentError`` unless ``value`` is one of ``choices``."""
    if value not in choices:
        raise InvalidArgumentError(
            f"invalid {name} {value!r}; valid choices: {', '.join(map(str, choices))}"
        )


class TrainingError(ImpactError):
    """Training cannot go on (e.g. a non-finite loss); nothing non-finite is written."""


class RenderingError(ImpactError):
    """No OpenGL context for MuJoCo's offscreen rendering (camera observations, ``render()``,
    ``impact-eval --video``); the message says which ``MUJOCO_GL`` to set (``impact_envs._gl``)."""
