"""Controller-config overrides from the command line (SECTION.FIELD=VALUE)."""

from __future__ import annotations

from dataclasses import replace

import pytest

from impact_control.config import ControllerConfig
from impact_control.errors import InvalidArgumentError
from impact_control.overrides import apply_overrides
from impact_control.presets import preset_config


def test_overrides_parse_by_field_type_and_leave_the_rest() -> None:
    base = ControllerConfig()
    cfg = apply_overrides(
        base,
        [
            "internal_model.slow_rate_max=1.5",
            "internal_model.update_every=8",
            "slow_wrench.rate_force_per_s=20",
            "impedance.stiffness_translational_n_per_m=800,800,800",
            "impedance.compensate_coriolis=false",
            "impedance.nullspace_damping_nms_per_rad=3",
            "estimator.kind=momentum",
        ],
    )
    assert cfg.internal_model.slow_rate_max == 1.5
    assert cfg.internal_model.update_every == 8 and isinstance(cfg.internal_model.update_every, int)
    assert cfg.slow_wrench.rate_force_per_s == 20.0
    assert cfg.impedance.stiffness_translational_n_per_m == (800.0, 800.0, 800.0)
    assert cfg.impedance.compensate_coriolis is False
    assert cfg.impedance.nullspace_damping_nms_per_rad == 3.0
    assert cfg.estimator.kind == "momentum"
    assert cfg.internal_model.learning_rate == base.internal_model.learning_rate
    assert cfg.slow_wrench.clip_force_n == base.slow_wrench.clip_force_n
    assert apply_overrides(base, []) == base


@pytest.mark.parametrize(
    ("item", "message"),
    [
        ("internal_model.slow_rate_max", "SECTION.FIELD=VALUE"),
        ("slow_rate_max=1", "SECTION.FIELD=VALUE"),
        ("brain.lr=1", "valid: ['estimator', 'guard', 'impedance', 'internal_model'"),
        ("internal_model.lr=1", "valid: ['history_length'"),
        ("internal_model.slow_rate_max=fast", "expected float"),
        ("impedance.compensate_gravity=maybe", "expected bool"),
        ("internal_model.slow_rate_max=-1", "valid: finite values > 0"),
        ("estimator.kind=kalman", "kalman"),
    ],
)
def test_bad_overrides_are_one_line_errors(item: str, message: str) -> None:
    with pytest.raises(InvalidArgumentError) as err:
        apply_overrides(ControllerConfig(), [item])
    assert message in str(err.value) and "\n" not in str(err.value)


def test_make_env_applies_overrides_and_resume_refuses_other_overrides() -> None:
    from impact_eval.envs import make_env
    from impact_eval.runinfo import RunIdentity, check_resumable

    env = make_env("IMPACT/Hammer-v1", "impact", ("internal_model.slow_rate_max=1.5",))
    assert env.unwrapped.controller.config.internal_model.slow_rate_max == 1.5
    env.close()
    plain = make_env("IMPACT/Hammer-v1", "impact")  # -v1: preset revision 1's default
    assert plain.unwrapped.controller.config == preset_config("default", revision=1)
    plain.close()
    v1 = make_env("IMPACT/Hammer-v1", "impact", ("internal_model.slow_rate_max=1.5",))
    assert not v1.unwrapped.controller.config.saturation_release.spare_carried  # overrides too
    v1.close()
    plain = make_env("IMPACT/Hammer-v2", "impact")
    assert plain.unwrapped.controller.config == ControllerConfig()
    plain.close()
    from impact_eval.spec import SweepSpec

    same = RunIdentity(SweepSpec("IMPACT/Hammer-v1", ("impact",), (1.0,), episodes=5),
                       "object_mass")
    previous = same.to_json()
    check_resumable(previous, same)
    with pytest.raises(InvalidArgumentError, match="controller_overrides"):
        other = ("slow_wrench.clip_force_n=5",)
        check_resumable(previous, replace(same, spec=replace(same.spec,
                                                             controller_overrides=other)))
