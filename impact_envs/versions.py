"""The envs' versions, in one place: each family's history, the id it registers, and the
one-line refusal of a retired id.

Gymnasium's convention is a new version for every change of behaviour, so that a number
published with an env id can be reproduced from that id. Until 2026-11-28 the five envs kept
``-v0`` through several changes of behaviour (below); ``-v1`` is the behaviour of the last
``-v0``, pinned under a new name (issue 41), and from now on a behaviour change bumps the
version here. ``-v0`` is retired rather than kept runnable: it named several behaviours, so a
``-v0`` number cannot be tied to one of them, and an alias would give one behaviour two names.
The committed tables that ran ``-v0`` keep saying so (they ran some ``-v0``; run.json records
the commit).

``-v2`` (issue 59, 2026-12-02) makes the robot as imperfect as a real FR3 by default
(``realism="fr3"``; HammerBasket keeps the authors' ideal robot) and the controller presets'
revision 2 (``default`` = ``keep_carried``). ``-v1`` is not retired: it stays registered with
everything that defines its behaviour pinned (``robot_realism``, ``preset_revision``), so a
table recorded on ``-v1`` reproduces at HEAD, as Gymnasium keeps ``Ant-v4`` beside ``Ant-v5``.

A checkpoint records the env its demonstrations were collected on (``meta.json``);
``checkpoints_from`` lists the versions whose checkpoints a version runs (the observation and
action spaces are unchanged from v0 to v2).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from impact_control.errors import InvalidArgumentError
from impact_control.presets import LATEST_REVISION

NAMESPACE = "IMPACT"
"""The Gymnasium namespace of the built-in envs (LeRobot's is ``gym_impact``)."""


@dataclass(frozen=True)
class Change:
    """One dated change of an env's behaviour or interface (``numbers`` False: no episode's
    numbers change)."""

    date: str
    text: str
    numbers: bool = True


@dataclass(frozen=True)
class EnvVersion:
    """One version: its number, what it is, the changes it went through while it was current
    (none for a pinned version), the versions whose checkpoints it runs, and what it pins.

    Attributes:
        robot_realism: The robot profile when ``RobotOptions.realism`` is not given
            (``REALISMS``: ``"ideal"`` or ``"fr3"``).
        preset_revision: The controller presets' revision its preset names resolve to
            (``impact_control.presets.REVISIONS``).
        retired: Refused by name (one line naming the current id) instead of registered.
    """

    version: int
    summary: str
    changes: tuple[Change, ...] = ()
    checkpoints_from: tuple[int, ...] = ()
    robot_realism: str = "ideal"
    preset_revision: int = 1
    retired: bool = False


_SHARED_V0 = (
    Change("2026-11-25", "bad input only: an action must have shape (10,) (others were "
           "flattened) and a parameter value must be a real number (bools and strings were "
           "coerced)", numbers=False),
    Change("2026-11-25", "constructor arguments grouped: sensor_noise, grasp_force_n and "
           "model_mass_error became fields of robot=RobotOptions(...); width, height and camera "
           "of render=RenderOptions(...); controller_preset also takes a ControllerConfig "
           "(replacing controller_config)", numbers=False),
    Change("2026-11-25", 'reward_type="dense" added (sparse stays the default)', numbers=False),
    Change("2026-11-26", 'pixel observations (observation=ObservationOptions(...)) and a "wrist" '
           'camera added; the default "state" mode is unchanged bit for bit', numbers=False),
    Change("2026-11-26", "estimator removed from the constructor: the wrench estimator is a "
           'field of the controller config (preset_config("default", estimator="momentum"))',
           numbers=False),
    Change("2026-11-27", 'controller_preset also takes "authors_sim" and "authors_real" (the '
           "paper authors' released controller); RobotOptions gains torque_reading (default "
           '"link_side", unchanged)', numbers=False),
    Change("2026-11-27", "the default preset gains the saturated-lift release "
           "(docs/controller.md): with a load the wrist cannot hold, the learned feedforward is "
           "let go after 0.5 s at a torque bound without the load rising; episodes that never "
           "stall at a bound are unchanged bit for bit, paper is unchanged"),
    Change("2026-11-27", "RobotOptions gains the realism fields (realism, per-link model "
           'errors, torque offsets, delay, lost commands, encoder steps); the default "ideal" '
           "is the earlier behaviour bit for bit", numbers=False),
)
_DEFAULT_PRESET = Change(
    "2026-11-24", "controller_preset added; the controller's default configuration changed "
    'from the paper-literal table (now controller_preset="paper", equal to the earlier '
    "defaults field for field) to the default preset")
_V1 = EnvVersion(1, "the behaviour of the last v0, pinned under a new name (issue 41, "
                 "2026-11-28); kept registered beside v2 with the ideal robot and preset "
                 "revision 1 pinned, so its tables reproduce (issue 59)",
                 checkpoints_from=(0, 1))
_V2 = EnvVersion(2, 'the robot as imperfect as a real FR3 by default (realism="fr3": '
                 "torque-sensor offsets, an averaged dynamics model, a one-tick delay, "
                 "quantized encoders; docs/sensing.md) and preset revision 2, whose default "
                 "is keep_carried (a load the arm has lifted is not let go; issue 59, "
                 "2026-12-02)", checkpoints_from=(0, 1, 2), robot_realism="fr3",
                 preset_revision=2)
_V2_BASKET = EnvVersion(2, "preset revision 2, whose default is keep_carried (issue 59, "
                        "2026-12-02); the robot stays the authors' ideal one",
                        checkpoints_from=(0, 1, 2), preset_revision=2)


def _v0(*changes: Change) -> EnvVersion:
    return EnvVersion(0, "initial release", changes, retired=True)


VERSIONS: dict[str, tuple[EnvVersion, ...]] = {
    "Hammer": (_v0(_DEFAULT_PRESET, *_SHARED_V0), _V1, _V2),
    "Dumbbell": (_v0(_DEFAULT_PRESET, *_SHARED_V0), _V1, _V2),
    "Calligraphy": (_v0(
        Change("2026-11-22", "the normal-axis feedforward hold moved from the task into the "
               "controller (held from the last unmasked tick instead of the last tick the tip "
               "was > 5 mm above the paper); pressing engages with the commanded tip within "
               "5 mm of the paper and releases above 10 mm (was: on exactly while within 2 mm)"),
        Change("2026-11-24", "while pressing, the learning mask freezes all three force axes "
               "(was: z only), and the default controller preset replaces the paper-literal "
               'one (controller_preset="paper")'),
        *_SHARED_V0), _V1, _V2),
    "Disturbance": (_v0(
        Change("2026-11-22", "the disturbance acts only while the trough is held"),
        Change("2026-11-24", "the default controller preset replaces the paper-literal one "
               '(controller_preset="paper")'),
        *_SHARED_V0), _V1, _V2),
    "HammerBasket": (EnvVersion(0, "initial release (2026-11-27)", (_SHARED_V0[-1],),
                                retired=True), _V1, _V2_BASKET),
}
"""Each family's versions, oldest first; the last is the current one, and every version not
``retired`` is registered."""

_ID = re.compile(r"^(?:(?P<module>[\w.]+):)?(?P<namespace>[\w]+)/(?P<family>\w+)-v(?P<v>\d+)$")


def current_version(family: str) -> int:
    """The version ``family`` registers (one line naming the families if unknown)."""
    if family not in VERSIONS:
        raise InvalidArgumentError(f"unknown env family {family!r}; valid: {', '.join(VERSIONS)}")
    return VERSIONS[family][-1].version


def current_id(family: str, namespace: str = NAMESPACE) -> str:
    """``"IMPACT/<family>-v<current>"``."""
    return f"{namespace}/{family}-v{current_version(family)}"


def registered(family: str) -> tuple[EnvVersion, ...]:
    """The versions of ``family`` that are registered (every one not retired), oldest first."""
    current_version(family)  # one line on an unknown family
    return tuple(v for v in VERSIONS[family] if not v.retired)


def version_info(family: str, version: int | None = None) -> EnvVersion:
    """Version ``version`` of ``family`` (None: the current one); a one-line error naming
    the registered versions for a retired or unknown one."""
    kept = registered(family)
    if version is None:
        return kept[-1]
    for v in kept:
        if v.version == version and not isinstance(version, bool):
            return v
    raise InvalidArgumentError(f"invalid env_version {version!r} for {family}; valid: "
                               f"{', '.join(str(v.version) for v in kept)}")


def parse(env_id: str) -> tuple[str, int] | None:
    """(family, version) of a built-in env id (any namespace, optional ``module:``); None
    for another env."""
    m = _ID.match(env_id)
    if m is None or m["family"] not in VERSIONS:
        return None
    return m["family"], int(m["v"])


OTHER_ENV_PINS = ("ideal", LATEST_REVISION)
"""(robot profile, preset revision) of an env outside the built-in families: it has one
version, the ideal robot and the latest presets."""


def pins(family: str | None, version: int | None = None) -> tuple[str, int]:
    """(robot profile when ``RobotOptions.realism`` is unset, controller preset revision) of
    ``family`` at ``version`` (None: the current one; ``family`` None: ``OTHER_ENV_PINS``).
    A retired or unknown version is a one-line error naming the registered ones."""
    if family is None:
        return OTHER_ENV_PINS
    v = version_info(family, version)
    return v.robot_realism, v.preset_revision


def pins_of(env_id: str) -> tuple[str, int]:
    """``pins`` of an env id (``OTHER_ENV_PINS`` for another env or a retired id, which is
    refused in its own line where it is made)."""
    parsed = parse(env_id)
    if parsed is None or retired(env_id) is not None:
        return OTHER_ENV_PINS
    return pins(*parsed)


def preset_revision(env_id: str) -> int:
    """The controller presets' revision ``env_id`` runs (``pins_of``)."""
    return pins_of(env_id)[1]


def robot_realism(env_id: str) -> str:
    """The robot profile ``env_id`` runs when ``RobotOptions.realism`` is unset (``pins_of``)."""
    return pins_of(env_id)[0]


def pinned_by(family: str, version: int) -> int:
    """The first registered version after ``version``: the one that pins a retired version's
    behaviour (``-v0`` -> ``-v1``)."""
    return next(v.version for v in registered(family) if v.version > version)


def version_of(env_id: str) -> int | None:
    """The version number of a built-in env id (None for another env)."""
    parsed = parse(env_id)
    return None if parsed is None else parsed[1]


def retired(env_id: str) -> str | None:
    """The one-line refusal of a retired version of a built-in env, None otherwise."""
    parsed = parse(env_id)
    if parsed is None or not any(v.retired and v.version == parsed[1]
                                 for v in VERSIONS[parsed[0]]):
        return None
    family, version = parsed
    then = env_id.replace(f"{family}-v{version}", f"{family}-v{pinned_by(family, version)}")
    now = env_id.replace(f"{family}-v{version}", f"{family}-v{current_version(family)}")
    also = "" if now == then else f", or {now}, the current version"
    return (f"{env_id} is retired (its behaviour changed under one name; "
            f"impact_envs/versions.py); use {then}, the behaviour of the last -v{version}{also}")


def check_not_retired(env_id: str) -> None:
    """Raise ``InvalidArgumentError`` (one line naming the current id) for a retired id."""
    message = retired(env_id)
    if message is not None:
        raise InvalidArgumentError(message)


def runs_checkpoint_of(env_id: str, trained_on: str) -> bool:
    """Whether ``env_id`` runs a checkpoint trained on ``trained_on``: the same family and
    a version in its ``checkpoints_from`` (ids outside the built-in families: equal ids)."""
    now, then = parse(env_id), parse(trained_on)
    if now is None or then is None:
        return env_id.rsplit(":", 1)[-1] == trained_on.rsplit(":", 1)[-1]
    version = next(v for v in VERSIONS[now[0]] if v.version == now[1])
    return now[0] == then[0] and then[1] in version.checkpoints_from


def history_markdown() -> str:
    """docs/envs.md's version table (tests/envs/test_versions.py checks the two agree)."""
    lines = ["| env | version | what | changes while current |", "|---|---|---|---|"]
    for family, versions in VERSIONS.items():
        for v in versions:
            changes = "; ".join(f"{c.date}: {c.text}" + ("" if c.numbers else
                                                          " (no number changes)")
                                for c in v.changes) or "none"
            lines.append(f"| {family} | v{v.version} | {v.summary} | {changes} |")
    return "\n".join(lines) + "\n"
