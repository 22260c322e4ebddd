"""``impact_experiments.end_early_check``: early rows pair with their full-length twins and a
flipped outcome fails the check."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from impact_experiments.end_early_check import main, paired, summary

COLUMNS = {"energy_j": 1.0, "peak_torque_nm": 2.0, "peak_contact_force_n": 3.0,
           "contact_over_20n_s": 0.0, "mean_pose_error_m": 0.01}


def _table(path: Path, rows: list[tuple]) -> Path:
    path.mkdir()
    pd.DataFrame([{"method": m, "param_value": v, "episode": e, "seed": 100 + e,
                   "success": s, "length": n, **COLUMNS} for m, v, e, s, n in rows]
                 ).to_csv(path / "episodes.csv", index=False)
    return path


def test_pairs_count_early_ends_and_savings(tmp_path: Path) -> None:
    full = _table(tmp_path / "full", [("a", 1.0, 0, 1, 1800), ("a", 1.0, 1, 0, 1800),
                                      ("a", 1.0, 2, 1, 1800)])
    early = _table(tmp_path / "early", [("a", 1.0, 0, 1, 600), ("a", 1.0, 1, 0, 1800)])
    both = paired(pd.read_csv(full / "episodes.csv"), pd.read_csv(early / "episodes.csv"))
    result = summary(both, 1800)["all"]
    assert (result["pairs"], result["flips"], result["ended_early"]) == (2, 0, 1)
    assert result["steps_saved_fraction"] == pytest.approx(1 - 2400 / 3600)
    assert main(["--full", str(full), "--early", str(early)]) == 0


def test_a_flip_fails_and_an_unpaired_row_is_one_line(tmp_path: Path, capsys) -> None:
    full = _table(tmp_path / "full", [("a", 1.0, 0, 0, 1800)])
    early = _table(tmp_path / "early", [("a", 1.0, 0, 1, 700)])
    assert main(["--full", str(full), "--early", str(early), "--out",
                 str(tmp_path / "s.json")]) == 1
    assert (tmp_path / "s.json").is_file()
    stray = _table(tmp_path / "stray", [("b", 1.0, 0, 1, 700)])
    with pytest.raises(SystemExit) as exc:
        main(["--full", str(full), "--early", str(stray)])
    assert exc.value.code == 2 and "no full-length twin" in capsys.readouterr().err
    mixed = _table(tmp_path / "mixed", [("a", 1.0, 0, 0, 700), ("b", 1.0, 0, 1, 700)])
    assert main(["--full", str(full), "--early", str(mixed), "--twins-only"]) == 0


def test_tables_of_two_cpus_are_refused_in_one_line(tmp_path: Path, capsys) -> None:
    """An outcome may flip across CPU families with the flag off: such a pairing proves
    nothing, so it is refused unless --across-cpus is given."""
    import json

    full = _table(tmp_path / "full", [("a", 1.0, 0, 1, 1800)])
    early = _table(tmp_path / "early", [("a", 1.0, 0, 1, 700)])
    for table, cpu in ((full, "Intel(R) Xeon(R) Processor"), (early, "AMD EPYC")):
        (table / "run.json").write_text(json.dumps({"host": {"cpu_model": cpu}}))
    with pytest.raises(SystemExit) as exc:
        main(["--full", str(full), "--early", str(early)])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1 and "different CPUs" in err
    assert main(["--full", str(full), "--early", str(early), "--across-cpus"]) == 0
    (full / "run.json").write_text(json.dumps({"host": {"cpu_model": "AMD EPYC"}}))
    assert main(["--full", str(full), "--early", str(early)]) == 0
