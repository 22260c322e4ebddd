"""Controller presets: the paper-literal table and the shipped default."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import numpy as np
import pytest

import impact_envs  # noqa: F401 - registers the envs
from impact_control.config import ControllerConfig
from impact_control.errors import InvalidArgumentError
from impact_control.overrides import apply_overrides
from impact_control.presets import (
    DEPARTURES,
    PRESETS,
    Preset,
    as_preset,
    preset_config,
    preset_name,
    resolve_preset,
    revert_departures,
)


def test_paper_preset_is_the_papers_table() -> None:
    cfg = preset_config("paper")
    assert cfg.slow_wrench.rate_force_per_s == 2.0 and cfg.slow_wrench.rate_torque_per_s == 1.0
    assert cfg.slow_wrench.clip_force_n == 10.0 and cfg.slow_wrench.clip_torque_nm == 1.0
    im = cfg.internal_model
    assert (im.learning_rate, im.surprise_open_n, im.slow_rate_max) == (0.01, 5.0, 0.2)
    assert im.history_length == 32
    assert cfg.impedance.stiffness_translational_n_per_m == (400.0, 400.0, 400.0)
    assert cfg.estimator.lowpass_time_constant_s == 0.0495


def test_default_differs_from_paper_exactly_in_the_listed_departures() -> None:
    default, paper = preset_config("default"), preset_config("paper")
    assert default == ControllerConfig()
    changed = set()
    for section in dataclasses.fields(default):
        a, b = getattr(default, section.name), getattr(paper, section.name)
        if dataclasses.is_dataclass(a):
            changed |= {f"{section.name}.{f.name}" for f in dataclasses.fields(a)
                        if getattr(a, f.name) != getattr(b, f.name)}
    assert changed == set(DEPARTURES)
    assert revert_departures(default, DEPARTURES) == paper
    for key in DEPARTURES:  # each revert alone changes exactly one field
        one = revert_departures(default, [key])
        # reverting spare_carried alone gives revision 1's default (the -v1 envs')
        named = "default" if key == "saturation_release.spare_carried" else "custom"
        assert one != default and preset_name(one, revision=1) == named


def test_revisions_pin_default_and_only_default() -> None:
    """Revision 1's default is the one the -v1 tables ran (spare_carried off); revision 2's
    is keep_carried; every other preset is equal in both revisions."""
    v1, v2 = preset_config("default", revision=1), preset_config("default", revision=2)
    assert not v1.saturation_release.spare_carried and v2.saturation_release.spare_carried
    assert v2 == ControllerConfig() == preset_config("keep_carried")
    assert dataclasses.replace(v1, saturation_release=v2.saturation_release) == v2
    for name in PRESETS[1:]:
        assert preset_config(name, revision=1) == preset_config(name, revision=2), name
    assert preset_name(v1) == "custom" and preset_name(v2, revision=1) == "keep_carried"
    assert resolve_preset("default", revision=1).config == v1
    with pytest.raises(InvalidArgumentError, match="valid: 1, 2"):
        preset_config("default", revision=3)


def test_preset_names_and_errors() -> None:
    # keep_carried equals the latest default (named default first); in revision 1 it differs
    assert [preset_name(preset_config(n, revision=1), revision=1) for n in PRESETS] == (
        list(PRESETS))
    assert [preset_name(preset_config(n)) for n in PRESETS] == [
        "default" if n == "keep_carried" else n for n in PRESETS]
    assert preset_name(apply_overrides(ControllerConfig(), ["slow_wrench.clip_force_n=3"])) == (
        "custom")
    with pytest.raises(InvalidArgumentError, match="valid choices: default, paper"):
        preset_config("fast")
    with pytest.raises(InvalidArgumentError, match="valid choices"):
        revert_departures(ControllerConfig(), ["impedance.stiffness_translational_n_per_m"])


def test_estimator_kind_is_chosen_on_the_preset() -> None:
    for name in ("default", "paper"):  # the authors' presets run their own observer
        assert preset_config(name, estimator="residual") == preset_config(name)
        momentum = preset_config(name, estimator="momentum")
        assert momentum.estimator.kind == "momentum" and preset_name(momentum) == "custom"
        assert dataclasses.replace(momentum, estimator=preset_config(name).estimator) == (
            preset_config(name))
    with pytest.raises(InvalidArgumentError, match="valid choices: residual, momentum"):
        preset_config("default", estimator="kalman")


@pytest.mark.parametrize(("env_id", "revision"), [("IMPACT/Hammer-v1", 1),
                                                  ("IMPACT/Hammer-v2", 2)])
def test_env_kwarg_selects_the_preset_and_info_reports_it(env_id: str, revision: int) -> None:
    for name in PRESETS:
        env = gym.make(env_id, controller_preset=name)
        _, info = env.reset(seed=0)
        assert env.unwrapped.controller.config == preset_config(name, revision=revision)
        assert info["controller_preset"] == name
        env.close()
    custom = apply_overrides(ControllerConfig(), ["internal_model.learning_rate=0.02"])
    env = gym.make("IMPACT/Hammer-v1", controller_preset=custom)
    assert env.reset(seed=0)[1]["controller_preset"] == "custom"
    env.close()
    with pytest.raises(InvalidArgumentError, match="valid choices: default, paper"):
        gym.make("IMPACT/Hammer-v1", controller_preset="literal")


def test_warm_start_restores_weights_and_replay_at_every_reset() -> None:
    env = gym.make("IMPACT/Hammer-v1")
    model = env.unwrapped.controller.internal_model
    fresh = model.snapshot()
    model.net.weights[0][...] += 0.01
    model.replay.add(np.ones(model.input_dim), np.full(6, 0.5), np.ones(6))
    warm = model.snapshot()
    env.unwrapped.warm_start(warm)
    for seed in (0, 1):
        env.reset(seed=seed)
        assert model.replay.count == 1 and model.replay.targets[0, 0] == 0.5
        for k, v in model.net.state_dict().items():
            np.testing.assert_array_equal(v, warm.weights[k])
        model.net.weights[0][...] += 1.0  # what learning in an episode would change
        model.replay.add(np.zeros(model.input_dim), np.zeros(6), np.ones(6))
    env.unwrapped.warm_start(None)
    env.reset(seed=0)
    assert model.replay.count == 0
    for k, v in model.net.state_dict().items():
        np.testing.assert_array_equal(v, fresh.weights[k])
    env.close()


@pytest.mark.parametrize("name", ["keep_carried", "lift_watch"])
def test_issue_54_presets_are_default_plus_their_fields_only(name: str) -> None:
    from impact_control.presets import KEEP_CARRIED, LIFT_WATCH

    # against revision 1's default (the one issue 54 added them to)
    fields = {"keep_carried": KEEP_CARRIED, "lift_watch": LIFT_WATCH}[name]
    watch, default = preset_config(name), preset_config("default", revision=1)
    assert watch != default and preset_name(watch, revision=1) == name
    assert apply_overrides(default, [f"{k}={v}" for k, v in fields.items()]) == watch
    assert dataclasses.replace(watch, saturation_release=default.saturation_release) == default
    assert default.saturation_release.lift_watch_s == float("inf")  # off in default
    assert not default.saturation_release.spare_carried


def test_a_preset_is_resolved_once_and_travels_with_its_name() -> None:
    """issue 57: the name and the config go together; the env never matches a config back to a
    name when it is given a ``Preset``."""
    assert resolve_preset("keep_carried") == Preset("keep_carried", preset_config("keep_carried"))
    tuned = resolve_preset("paper", ["internal_model.learning_rate=0.02"])
    assert tuned.name == "custom" and tuned.config.internal_model.learning_rate == 0.02
    # a bare config equal to a preset is named after it (users who build one themselves)
    assert as_preset(preset_config("paper")).name == "paper"
    assert as_preset(preset_config("keep_carried"), revision=1).name == "keep_carried"
    assert as_preset(tuned) is tuned
    with pytest.raises(InvalidArgumentError, match="invalid controller_preset 'literal'"):
        resolve_preset("literal")
    # a Preset's name is the env's, as given: the default config under a name of its own
    env = gym.make("IMPACT/Hammer-v1", controller_preset=Preset("mine", ControllerConfig()))
    assert env.unwrapped.controller_preset == "mine"
    assert env.unwrapped.controller.config == ControllerConfig()
    env.close()

