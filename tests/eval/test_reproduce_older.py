"""impact-eval reproduce on a committed table recorded before columns were added to
episodes.csv (``metrics.ADDED_COLUMNS``): the rerun writes today's columns, the check compares
the table's own columns value for value (on the recording CPU and on another), and an edit
in those columns still fails."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from fixtures.reproduce_fake import (
    OTHER_CPU,
    TABLE,
    edit_rows,
    episodes_path,
    read_table,
    record_fake_table,
    reproduce,
    set_cpu,
    set_entry,
    write_table,
)

from impact_eval.metrics import ADDED_COLUMNS
from impact_eval.reproduce_manifest import sha256

NEWEST = ADDED_COLUMNS["2026-11-27"]


def rerecord(results: Path) -> None:
    """The manifest agrees with the committed file as it is (``--record`` writes today's
    columns only: an older table is recorded by its digest and row count)."""
    set_entry(results, episodes_sha256=sha256(episodes_path(results)),
              rows=len(read_table(results)))


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The fake table as an older impact-eval wrote it: without the newest columns."""
    results = record_fake_table(tmp_path_factory.mktemp("older") / "results")
    write_table(results, [{k: v for k, v in row.items() if k not in NEWEST}
                          for row in read_table(results)])
    rerecord(results)
    return results


@pytest.fixture()
def results(recorded: Path, tmp_path: Path) -> Path:
    return Path(shutil.copytree(recorded, tmp_path / "results"))


@pytest.mark.parametrize("cpu", ["same", "other"])
@pytest.mark.parametrize("cells", [[], ["--cells", "fake_fast@1"]])
def test_an_older_table_is_compared_on_its_own_columns(results: Path, capsys, cpu: str,
                                                       cells: list[str]) -> None:
    assert not set(NEWEST) & set(read_table(results)[0])
    if cpu == "other":
        set_cpu(results, OTHER_CPU)
    code, out, _ = reproduce(results, capsys, "--check", TABLE, *cells)
    assert code == 0, out
    assert "predates the columns " + ", ".join(NEWEST) in out
    assert "identical to the committed values" in out


@pytest.mark.parametrize("cpu", ["same", "other"])
def test_an_older_table_that_differs_in_its_own_columns_fails(results: Path, capsys,
                                                             cpu: str) -> None:
    row = read_table(results)[4]  # recorded with another float: the rerun differs there
    edit_rows(results, {4: {"energy_j": repr(float(row["energy_j"]) + 0.125)}})
    rerecord(results)
    if cpu == "other":
        set_cpu(results, OTHER_CPU)
    code, out, _ = reproduce(results, capsys, "--check", TABLE, "--cells",
                             f"{row['method']}@{row['param_value']}")
    assert "columns energy_j" in out and "DIFFERENT to the committed values" in out
    if cpu == "same":
        assert code == 1 and "FAIL: rerun on the recording CPU" in out
    else:  # a float alone is no outcome flip: the cross-CPU rule passes it, and says so
        assert code == 0 and "0 of 3 rerun episodes flipped outcome" in out
