"""``impact-collect --controller-preset`` (issue 55 item 3): demos recorded under a named
controller configuration, e.g. the authors' baselines' controller (``--controller impedance
--controller-preset authors_sim``), and the store says which."""

from __future__ import annotations

import pytest

from impact_control.errors import InvalidArgumentError
from impact_learn.collect import build_parser, config_from_args, default_env_factory, store_attrs
from impact_learn.collect_config import CollectConfig


def test_the_preset_reaches_the_env_and_the_store(tmp_path) -> None:
    args = build_parser().parse_args(["--env", "IMPACT/HammerBasket-v1", "--out",
                                      str(tmp_path / "d.zarr"), "--mass", "0.5",
                                      "--controller-preset", "authors_sim"])
    cfg = config_from_args(args)
    assert (cfg.controller, cfg.controller_preset) == ("impedance", "authors_sim")
    env = default_env_factory(cfg)()
    _, info = env.reset(seed=0)
    assert info["controller_preset"] == "authors_sim" and info["object_mass"] == 0.5
    env.close()
    assert store_attrs(cfg, "object_mass")["controller_preset"] == "authors_sim"
    plain = CollectConfig(env_id="IMPACT/HammerBasket-v1", out=str(tmp_path / "e.zarr"))
    assert store_attrs(plain, "object_mass")["controller_preset"] == "default"  # as before


def test_a_bad_preset_is_one_line_naming_the_valid_ones(tmp_path, capsys) -> None:
    with pytest.raises(InvalidArgumentError, match="valid choices: default, paper"):
        CollectConfig(env_id="IMPACT/Hammer-v1", out=str(tmp_path / "d.zarr"),
                      controller_preset="theirs")
    from impact_learn.collect import main

    with pytest.raises(SystemExit) as exit_:
        main(["--env", "IMPACT/Hammer-v1", "--out", str(tmp_path / "d.zarr"),
              "--controller-preset", "theirs"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "invalid controller preset 'theirs'" in err
    assert not (tmp_path / "d.zarr").exists()
