"""impact-eval reproduce: the committed file against the manifest (any CPU, before any rerun),
every differing row named, bytes on the recording CPU, the outcome rule on another (faked
here: the manifest's recording CPU, or ``cpu_info``, set to another), and K.

A table "recorded" with other outcomes or floats is made by editing the committed rows and
recording the manifest again (``rerecord``): the rerun then differs exactly there.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import pytest
from fixtures.reproduce_fake import (
    OTHER_CPU,
    ROWS,
    TABLE,
    edit_rows,
    flip,
    read_table,
    record_fake_table,
    reproduce,
    rerecord,
    set_cpu,
    write_table,
)

from impact_eval import reproduce as reproduce_module
from impact_eval.reproduce_compare import (
    CROSS_CPU_EPISODES,
    CROSS_CPU_FLIPS,
    FALSE_FAIL_PROBABILITY,
    RowDiff,
    _binomial_cdf,
    flip_rate_bound,
    max_outcome_flips,
    row_lines,
)

FLOAT = "energy_j"


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return record_fake_table(tmp_path_factory.mktemp("recorded") / "results")


@pytest.fixture()
def results(recorded: Path, tmp_path: Path) -> Path:
    return Path(shutil.copytree(recorded, tmp_path / "results"))


def _float_edit(row: dict[str, str]) -> dict[str, str]:
    return {FLOAT: repr(float(row[FLOAT]) + 0.125)}


# --- the committed file against the manifest: any CPU, before any rerun ---------------------

@pytest.mark.parametrize("cpu", ["same", "other"])
@pytest.mark.parametrize("index,column", [(0, "success"), (7, FLOAT), (17, "success_once"),
                                          (11, "peak_contact_force_n")])
def test_an_edited_committed_file_fails_before_any_rerun(results: Path, capsys, cpu: str,
                                                         index: int, column: str) -> None:
    if cpu == "other":
        set_cpu(results, OTHER_CPU)
    row = read_table(results)[index]
    edit_rows(results, {index: {column: "1" if row[column] == "0" else "0"}})
    for cells in ([], ["--cells", f"{row['method']}@{row['param_value']}"],
                  ["--cells", "fake_fast@0.5" if row["method"] != "fake_fast" else "fake_slow@3"]):
        code, out, _ = reproduce(results, capsys, "--check", TABLE, *cells)
        assert code == 1, out
        assert "FAIL before any rerun: the committed" in out and "edited or damaged" in out
        assert "library versions here" not in out  # nothing rerun


def test_a_removed_committed_row_fails_before_any_rerun(results: Path, capsys) -> None:
    write_table(results, read_table(results)[:-1])
    code, out, _ = reproduce(results, capsys, "--check", TABLE, "--cells", "fake_fast@1")
    assert code == 1 and "FAIL before any rerun" in out


def test_a_damaged_row_count_in_the_manifest_fails(results: Path, capsys) -> None:
    from fixtures.reproduce_fake import set_entry

    set_entry(results, rows=ROWS + 1)
    code, out, _ = reproduce(results, capsys, "--check", TABLE)
    assert code == 1 and f"has {ROWS} rows, the manifest {ROWS + 1}" in out


# --- the recording CPU: bytes ---------------------------------------------------------------

def test_on_the_recording_cpu_a_float_difference_fails_and_names_the_row(results: Path,
                                                                         capsys) -> None:
    row = read_table(results)[4]
    edit_rows(results, {4: _float_edit(row)})
    rerecord(results)  # the manifest's CPU is this one
    code, out, _ = reproduce(results, capsys, "--check", TABLE)
    assert code == 1, out
    name = f"{row['method']} @ {float(row['param_value']):g} episode {row['episode']}"
    assert f"differs: fake: {name}: columns {FLOAT}" in out
    assert "FAIL: rerun on the recording CPU" in out and "DIFFERENT" in out


# --- another CPU: outcomes within K, nothing missing or extra -------------------------------

def test_on_another_cpu_float_differences_pass_and_say_so(results: Path, capsys) -> None:
    rows = read_table(results)
    edit_rows(results, {2: _float_edit(rows[2]), 13: _float_edit(rows[13])})
    rerecord(results)
    set_cpu(results, OTHER_CPU)
    code, out, _ = reproduce(results, capsys, "--check", TABLE)
    assert code == 0, out
    assert out.count(f": columns {FLOAT}") == 2  # both rows named
    assert "DIFFERENT to the committed bytes" in out and "2 rows differ" in out
    assert "another CPU, so bytes are compared only on the recording CPU" in out
    assert f"here 0 of {ROWS} rerun episodes flipped outcome" in out
    assert f"at most K={max_outcome_flips(ROWS)} allowed" in out and out.rstrip().endswith("PASS")


@pytest.mark.parametrize("flips", [1, max_outcome_flips(ROWS), max_outcome_flips(ROWS) + 1])
def test_on_another_cpu_at_most_k_outcomes_may_flip(results: Path, capsys, flips: int) -> None:
    rows = read_table(results)
    indices = [0, 5, 9, 14, 17][:flips]
    edit_rows(results, {i: flip(rows[i]) for i in indices})
    rerecord(results)
    set_cpu(results, OTHER_CPU)
    code, out, _ = reproduce(results, capsys, "--check", TABLE)
    k = max_outcome_flips(ROWS)
    assert code == (0 if flips <= k else 1), out
    assert f"here {flips} of {ROWS} rerun episodes flipped outcome" in out
    assert out.rstrip().endswith("PASS" if flips <= k else "FAIL")
    assert out.count("columns success ") == flips  # every flipped row named, committed -> rerun


def test_other_cpu_via_cpu_info_counts_only_the_rerun_cells(results: Path, capsys,
                                                            monkeypatch) -> None:
    """The other path, faked from the other side: this machine's CPU reported as different."""
    rows = read_table(results)
    cell = [i for i, r in enumerate(rows)
            if (r["method"], r["param_value"]) == ("fake_slow", "1.0")]
    edit_rows(results, {cell[0]: flip(rows[cell[0]])})
    rerecord(results)
    monkeypatch.setattr(reproduce_module, "cpu_info", lambda: dict(OTHER_CPU))
    code, out, _ = reproduce(results, capsys, "--check", TABLE, "--cells", "fake_slow@1")
    assert code == 0, out
    assert "here 1 of 3 rerun episodes flipped outcome" in out and "K=1" in out
    assert "success 1 -> 0" in out or "success 0 -> 1" in out
    edit_rows(results, {cell[1]: flip(rows[cell[1]])})
    rerecord(results)
    code, out, _ = reproduce(results, capsys, "--check", TABLE, "--cells", "fake_slow@1")
    assert code == 1 and "here 2 of 3 rerun episodes flipped" in out and "FAIL" in out


@pytest.mark.parametrize("cells", [[], ["--cells", "fake_fast@3"]])
def test_on_another_cpu_a_missing_row_fails(results: Path, capsys, cells: list[str]) -> None:
    rows = read_table(results)
    write_table(results, rows[:6] + rows[7:])  # fake_fast @ 3, episode 0 never recorded
    rerecord(results)
    set_cpu(results, OTHER_CPU)
    code, out, _ = reproduce(results, capsys, "--check", TABLE, *cells)
    assert code == 1, out
    assert "not in the committed file" in out and "1 rows missing or extra" in out


def test_on_another_cpu_rows_outside_the_rerun_cells_must_be_equal(results: Path,
                                                                  capsys) -> None:
    rows = read_table(results)
    write_table(results, rows[1:])  # a row of fake_fast @ 0.5 missing: resumed outside the cell
    rerecord(results)
    set_cpu(results, OTHER_CPU)
    code, out, _ = reproduce(results, capsys, "--check", TABLE, "--cells", "fake_slow@3")
    assert code == 1 and "1 rows differ outside the rerun cells: FAIL" in out


# --- K and row naming (no rerun) --------------------------------------------------------------

def test_k_is_the_documented_binomial_bound() -> None:
    assert (CROSS_CPU_FLIPS, CROSS_CPU_EPISODES) == (1, 180)
    assert flip_rate_bound() == pytest.approx(0.02608, abs=5e-5)
    assert [max_outcome_flips(n) for n in (0, 18, 80, 100, 2100)] == [0, 3, 6, 7, 72]
    assert max_outcome_flips(100) >= 1 and max_outcome_flips(80) >= 0  # the measurements pass


@pytest.mark.parametrize("n", [1, 3, 18, 80, 100, 500])
def test_k_is_the_smallest_count_exceeded_at_most_one_percent_of_the_time(n: int) -> None:
    p, k = flip_rate_bound(), max_outcome_flips(n)
    assert 1 - _binomial_cdf(k, n, p) <= FALSE_FAIL_PROBABILITY
    assert k == 0 or 1 - _binomial_cdf(k - 1, n, p) > FALSE_FAIL_PROBABILITY
    assert max_outcome_flips(n + 1) >= k


@pytest.mark.parametrize("episodes", [20, 180, 1000])
def test_the_rate_bound_matches_the_closed_form_without_flips(episodes: int) -> None:
    assert flip_rate_bound(0, episodes) == pytest.approx(1 - 0.05 ** (1 / episodes), rel=1e-6)
    assert math.isclose(_binomial_cdf(0, episodes, 0.01), 0.99 ** episodes, rel_tol=1e-9)


def test_row_lines_put_flips_first_and_say_how_many_were_not_printed() -> None:
    floats = [RowDiff(("m", "1.0", e), ("energy_j",), ()) for e in range(40)]
    flipped = RowDiff(("m", "2.0", 3), ("success", "energy_j"), ("success 1 -> 0",))
    missing = RowDiff(("n", "0.5", 0), (), (), "missing in the rerun")
    lines = row_lines([*floats, flipped, missing], limit=10)
    assert lines[0] == "m @ 2 episode 3: columns success 1 -> 0, energy_j"
    assert lines[1] == "n @ 0.5 episode 0: missing in the rerun"
    assert lines[-1].startswith("... and 32 more differing rows not printed")
    assert len(lines) == 11 and row_lines(floats[:3]) == [r.line() for r in floats[:3]]
