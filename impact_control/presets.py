"""Named controller presets: ``"default"`` (the shipped configuration), ``"paper"``,
``"keep_carried"`` (the saturated-lift release spares a lifted load: ``KEEP_CARRIED``, issue
54; ``default`` since revision 2), ``"lift_watch"`` (experimental: ``default`` with the lift
watch, ``LIFT_WATCH``), and the
authors' released controller as it runs in their simulation (``"authors_sim"``) and on their
robot (``"authors_real"``; ``authors_presets.py``).

``paper`` is the literal reading of the IMPACT paper's hyper-parameter table, exactly the
defaults this project shipped until 2026-11-24 (every field equal, bit for bit).
``default`` departs from it in the fields listed in ``DEPARTURES``, each chosen by measurement
on tuning seeds and justified in docs/presets.md ("Presets"); the ablation that reverts
each one alone is in docs/results.md.

    ControllerConfig()                     # the "default" preset (of the latest revision)
    preset_config("paper")                 # the paper-literal table
    gym.make("IMPACT/Hammer-v2", controller_preset="paper")
    preset_config("default", estimator="momentum")  # the momentum-observer estimator
    preset_config("default", revision=1)   # the default of the -v1 envs

Revisions: a preset name keeps its values for ever within a revision (``REVISIONS``). The
envs pin theirs (``impact_envs/versions.py``: ``-v1`` runs revision 1, ``-v2`` revision 2), so a
table recorded on ``-v1`` reproduces whatever ``default`` is now; ``impact-robot`` and
``ControllerConfig()`` are the latest revision.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

from impact_control.authors_presets import AUTHORS_PRESETS, SIM_ONLY, authors_config
from impact_control.config import ControllerConfig
from impact_control.errors import InvalidArgumentError, check_choice
from impact_control.overrides import apply_overrides

PRESETS: tuple[str, ...] = ("default", "paper", "keep_carried", "lift_watch",
                             *AUTHORS_PRESETS)
"""Valid preset names."""

KEEP_CARRIED: dict[str, str] = {
    "saturation_release.spare_carried": "True",
}
"""Fields where ``keep_carried`` differs from the revision-1 ``default`` (issue 54's preset,
chosen on tuning seeds on Hammer and HammerBasket, docs/presets.md "Keep carried"; equal to
``default`` from revision 2, the name kept so that its tables and commands still run): once
the TCP has risen 20 mm since the gripper closed, the saturated-lift release no longer scales
the feedforward down, so a load the arm has lifted is carried, not let go, while the wrist is
at its bound."""

LIFT_WATCH: dict[str, str] = {
    "saturation_release.lift_watch_s": "4.0",
    "saturation_release.spare_carried": "True",
}
"""Fields where ``lift_watch`` differs from ``default`` (issue 54: a learned load is fed
forward only while the arm carries it; ``saturation_release.py``, "Lift watch"). Experimental,
not adopted: its reference-seed check loses lifts (docs/presets.md, "Lift watch")."""
REVISIONS: dict[int, dict[str, str]] = {
    1: {"saturation_release.spare_carried": "False"},
    2: {},
}
"""The presets' revisions: for each, the fields where its ``default`` differs from
``ControllerConfig()`` (``SECTION.FIELD`` keys). Revision 1 is ``default`` until 2026-12-02
(issue 59), whose saturated-lift release also lets go of a load the arm has lifted; revision 2
makes ``keep_carried`` the ``default`` (docs/presets.md, "Keep carried"). Only ``default``
differs between revisions: every other preset sets the field itself or reverts it
(``DEPARTURES``)."""
LATEST_REVISION = max(REVISIONS)
"""The revision of ``ControllerConfig()``, of ``impact-robot`` and of the current envs."""

ROBOT_PRESETS: tuple[str, ...] = tuple(name for name in PRESETS if name not in SIM_ONLY)
"""The presets that may run on a real FR3 (``impact-robot --preset``): all but
``SIM_ONLY``'s."""

DEPARTURES: dict[str, str] = {
    "internal_model.slow_rate_max": "0.2",
    "slow_wrench.rate_force_per_s": "2.0",
    "internal_model.learning_rate": "0.01",
    "internal_model.surprise_open_n": "5.0",
    "guard.enabled": "False",
    "limits.rate_limiter": "per_tick_clip",
    "limits.torque_rate_max_nm_per_s": "1000.0",
    "internal_model.learner": "numpy",
    "saturation_release.enabled": "False",
    "saturation_release.spare_carried": "False",
}
"""Fields where ``default`` differs from ``paper``, with the paper's value (``SECTION.FIELD``
keys, the syntax of ``--controller-set``; ``revert_departure`` applies one)."""


@dataclass(frozen=True)
class Preset:
    """A controller configuration and the name it travels under, resolved once
    (``resolve_preset``) and carried together to the env, its ``info["controller_preset"]``
    and the run's records: nothing downstream turns a config back into a name.

    Attributes:
        name: one of ``PRESETS``, or ``"custom"`` (a preset with ``SECTION.FIELD=VALUE``
            overrides, or a ``ControllerConfig`` given as it is that equals no preset).
        config: the controller's configuration.
    """

    name: str
    config: ControllerConfig


CUSTOM = "custom"
"""The name of a configuration that is no preset as it stands."""


def resolve_preset(name: str, overrides: Sequence[str] = (),
                   label: str = "controller_preset",
                   revision: int = LATEST_REVISION) -> Preset:
    """Preset ``name`` (one of ``PRESETS``; a one-line error naming them, as ``label``) of
    ``revision`` with ``SECTION.FIELD=VALUE`` ``overrides`` applied
    (``impact_control.overrides``): named ``name`` without overrides, ``"custom"`` with them."""
    check_choice(label, name, PRESETS)
    config = _preset_config(name, revision=_revision(revision))
    if overrides:
        return Preset(CUSTOM, apply_overrides(config, list(overrides)))
    return Preset(name, config)


def as_preset(given: str | ControllerConfig | Preset,
              revision: int = LATEST_REVISION) -> Preset:
    """What an env's ``controller_preset`` argument was given, as a ``Preset`` of
    ``revision``: a name is resolved, a ``Preset`` kept, and a bare ``ControllerConfig`` named
    after the preset it equals field for field (else ``"custom"``): the one place a config is
    matched to a name, for users who build a config themselves."""
    if isinstance(given, Preset):
        return given
    if isinstance(given, ControllerConfig):
        return Preset(preset_name(given, revision), given)
    return resolve_preset(given, revision=revision)


def preset_config(name: str, estimator: str | None = None,
                  revision: int = LATEST_REVISION) -> ControllerConfig:
    """The ``ControllerConfig`` of preset ``name`` (one of ``PRESETS``) of ``revision`` (one
    of ``REVISIONS``), with the wrench estimator of kind ``estimator`` (``ESTIMATOR_KINDS``:
    "residual", the presets', or "momentum") when given."""
    check_choice("controller preset", name, PRESETS)
    return _preset_config(name, estimator, _revision(revision))


def _revision(revision: int) -> int:
    if isinstance(revision, bool) or revision not in REVISIONS:
        raise InvalidArgumentError(f"invalid preset revision {revision!r}; valid: "
                                   f"{', '.join(map(str, REVISIONS))}")
    return revision


def _preset_config(name: str, estimator: str | None = None,
                   revision: int = LATEST_REVISION) -> ControllerConfig:
    if name in AUTHORS_PRESETS:
        if estimator is not None:
            raise InvalidArgumentError(
                f"invalid estimator {estimator!r} with preset {name!r} (it runs the authors' "
                "observer); valid: an estimator with preset default or paper")
        return authors_config(robot=name == "authors_real")
    config = ControllerConfig()
    if name == "default" and REVISIONS[revision]:
        config = apply_overrides(config, [f"{k}={v}" for k, v in REVISIONS[revision].items()])
    if name == "paper":
        config = revert_departures(config, DEPARTURES)
    elif name in ("keep_carried", "lift_watch"):
        fields = KEEP_CARRIED if name == "keep_carried" else LIFT_WATCH
        config = apply_overrides(config, [f"{k}={v}" for k, v in fields.items()])
    if estimator is None:
        return config
    return replace(config, estimator=replace(config.estimator, kind=estimator))


def revert_departures(config: ControllerConfig, keys: object) -> ControllerConfig:
    """``config`` with the listed ``DEPARTURES`` keys set back to the paper's values."""
    for key in keys:  # type: ignore[attr-defined]
        check_choice("departure", key, tuple(DEPARTURES))
    return apply_overrides(config, [f"{key}={DEPARTURES[key]}" for key in keys])  # type: ignore[attr-defined]


def preset_name(config: ControllerConfig, revision: int = LATEST_REVISION) -> str:
    """Name of the preset of ``revision`` that ``config`` equals field for field (the first
    in ``PRESETS``: ``default`` before its equal ``keep_carried``), else ``"custom"``."""
    for name in PRESETS:
        if _preset_config(name, revision=_revision(revision)) == config:
            return name
    return CUSTOM


def check_robot_preset(name: str) -> str:
    """``name`` if it is one of ``ROBOT_PRESETS``, else a one-line ``InvalidArgumentError``
    (naming why a simulation-only preset may not run on a robot)."""
    if name in SIM_ONLY:
        raise InvalidArgumentError(f"invalid preset {name!r} on a robot: {SIM_ONLY[name]}; "
                                   f"valid: {', '.join(ROBOT_PRESETS)}")
    check_choice("preset", name, ROBOT_PRESETS)
    return name
