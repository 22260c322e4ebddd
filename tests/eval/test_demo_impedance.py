"""``+demo_impedance``: a checkpoint's policy runs on the impedance its demos were recorded
under, the rest of the controller from the method's preset (docs/eval.md)."""

from __future__ import annotations

import json
import shutil
from dataclasses import fields
from pathlib import Path

import pytest

from impact_control.errors import CheckpointError, InvalidArgumentError
from impact_control.presets import PRESETS, REVISIONS, resolve_preset
from impact_envs.versions import preset_revision
from impact_eval.checkpoints import CHECKPOINTS_ENV_VAR
from impact_eval.envs import method_env
from impact_eval.methods import resolve_method

HB = "IMPACT/HammerBasket-v2"
SHIPPED = Path(__file__).parents[2] / "impact_envs" / "checkpoints"


def test_the_impedance_is_the_demos_and_every_other_section_the_presets() -> None:
    spec = resolve_method("dp.vanilla_authors+impact@keep_carried+demo_impedance")
    assert spec.impedance_preset(HB) == "authors_sim"  # the checkpoint's meta.json
    assert spec.settings_for(HB)["impedance_preset"] == "authors_sim"
    assert "impedance_preset" not in resolve_method("impact").settings_for(HB)
    assert spec.env_key(HB) != resolve_method("dp.vanilla_authors+impact@keep_carried").env_key(HB)
    env = method_env(HB, spec)
    try:
        config = env.unwrapped.controller.config
        revision = preset_revision(HB)
        theirs = resolve_preset("authors_sim", revision=revision).config
        ours = resolve_preset("keep_carried", revision=revision).config
        assert config.impedance == theirs.impedance != ours.impedance
        assert [f.name for f in fields(config)
                if getattr(config, f.name) != getattr(ours, f.name)] == ["impedance"]
    finally:
        env.close()


def test_a_policy_without_a_checkpoint_is_refused_in_one_line() -> None:
    with pytest.raises(InvalidArgumentError, match="valid: a dp.<variant> policy"):
        resolve_method("scripted+impact+demo_impedance")


def test_a_checkpoint_that_records_no_demo_preset_is_one_line(tmp_path: Path,
                                                              monkeypatch) -> None:
    """Checkpoints collected before the attribute existed record none: refused, not guessed."""
    copy = tmp_path / "hammerbasket" / "vanilla_authors"
    shutil.copytree(SHIPPED / "hammerbasket" / "vanilla_authors", copy)
    meta = json.loads((copy / "meta.json").read_text())
    del meta["dataset"]["attrs"]["controller_preset"]
    (copy / "meta.json").write_text(json.dumps(meta))
    monkeypatch.setenv(CHECKPOINTS_ENV_VAR, str(tmp_path))
    spec = resolve_method("dp.vanilla_authors+impact+demo_impedance")
    with pytest.raises(CheckpointError, match="records no demo controller preset"):
        spec.impedance_preset(HB)


def test_every_presets_impedance_is_the_same_in_every_revision() -> None:
    """The demos' preset is resolved at the evaluated env's revision, not at the one the demos
    ran (their env id's): the same section while no revision changes an impedance."""
    for name in PRESETS:
        sections = {revision: resolve_preset(name, revision=revision).config.impedance
                    for revision in REVISIONS}
        assert len(set(sections.values())) == 1, (name, sections)
