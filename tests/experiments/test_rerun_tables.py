"""The full rerun's driver (impact_experiments/rerun_tables.py): which tables it reruns
and with which env id."""

from __future__ import annotations

from impact_experiments.rerun_tables import current_args, is_current


def test_a_retired_env_id_is_rerun_on_its_current_version() -> None:
    args = ["--env", "IMPACT/Hammer-v0", "--method", "impact", "--seed", "0"]
    assert current_args(args) == ["--env", "IMPACT/Hammer-v1", "--method", "impact",
                                  "--seed", "0"]
    assert current_args(["--env", "mod:IMPACT/Dumbbell-v0"])[1] == "mod:IMPACT/Dumbbell-v1"
    assert current_args(["--env", "ImpactTest/Fake-v0"])[1] == "ImpactTest/Fake-v0"


def test_a_table_recorded_on_the_current_version_is_skipped() -> None:
    old = {"sweep_args": ["--env", "IMPACT/Hammer-v0"]}
    assert not is_current(old)
    assert not is_current({**old, "env_version": 0})
    assert is_current({"sweep_args": ["--env", "IMPACT/Hammer-v1"], "env_version": 1})
    assert is_current({"sweep_args": ["--env", "ImpactTest/Fake-v0"]})


def test_an_unknown_table_is_one_line(capsys) -> None:
    import pytest

    from impact_experiments.rerun_tables import main

    with pytest.raises(SystemExit) as info:
        main(["no_such_table"])
    err = capsys.readouterr().err.strip().splitlines()
    assert info.value.code == 2 and len(err) == 1 and "valid: " in err[0] and "main_job" in err[0]


def _results(tmp_path):
    """A results folder whose one table ``t`` still names -v0 (so it would be rerun)."""
    import json

    results = tmp_path / "results"
    (results / "t").mkdir(parents=True)
    (results / "t" / "episodes.csv").write_text("method,param_value,episode\na,1,0\n")
    entry = {"sweep_args": ["--env", "IMPACT/Hammer-v0", "--method", "impact"]}
    (results / "manifest.json").write_text(json.dumps({"tables": {"t": entry}}))
    return results


def _fake_python(tmp_path, sweep: str):
    """An executable that answers the interpreter probe as Python would and runs ``sweep``
    (shell) in place of a sweep."""
    script = tmp_path / "python"
    script.write_text("#!/bin/sh\n"
                      'if [ "$1" = "-c" ]; then echo impact_eval; exit 0; fi\n' + sweep + "\n")
    script.chmod(0o755)
    return script


def _files(root) -> dict:
    return {str(p.relative_to(root)): p.read_bytes() if p.is_file() else b"/"
            for p in sorted(root.rglob("*"))}


def _refused(capfd, argv: list[str]) -> str:
    """``rerun_tables ARGV`` exits 2 with one stderr line, no traceback."""
    import pytest

    from impact_experiments.rerun_tables import main

    with pytest.raises(SystemExit) as info:
        main(argv)
    err = capfd.readouterr().err.splitlines()
    assert info.value.code == 2 and len(err) == 1, err
    assert err[0].startswith("rerun_tables: error: ")
    return err[0]


def test_workers_below_one_or_not_an_integer_is_one_line(tmp_path, capfd) -> None:
    results = _results(tmp_path)
    for bad in ("0", "-2", "two", "1.5"):
        line = _refused(capfd, [f"--workers={bad}", "--results", str(results)])
        assert f"argument --workers: {bad!r} is not an integer >= 1" in line
    assert not (results / ".rerun").exists()


def test_a_bad_results_is_one_line(tmp_path, capfd) -> None:
    line = _refused(capfd, ["--results", str(tmp_path / "missing")])
    assert line == f"rerun_tables: error: no manifest.json in {tmp_path / 'missing'}"
    (tmp_path / "manifest.json").write_text('{"tables": ')
    line = _refused(capfd, ["--results", str(tmp_path)])
    assert line.startswith(f"rerun_tables: error: cannot read {tmp_path / 'manifest.json'}: ")


def test_a_python_that_cannot_run_the_sweeps_is_one_line_before_anything_runs(
        tmp_path, capfd) -> None:
    results = _results(tmp_path)
    before = _files(results)
    missing = tmp_path / "no_such_python"
    line = _refused(capfd, ["--python", str(missing), "--results", str(results)])
    assert line == f"rerun_tables: error: --python {missing}: no such executable"
    for program in ("/bin/false", "/bin/echo"):  # runs, but is not a Python with the package
        line = _refused(capfd, ["--python", program, "--results", str(results)])
        assert line.startswith(f"rerun_tables: error: --python {program} cannot import "
                               "impact_eval: ")
    no_package = _fake_python(tmp_path, "exit 0")
    no_package.write_text("#!/bin/sh\necho 'ModuleNotFoundError: No module named impact_eval' "
                          ">&2\nexit 1\n")
    line = _refused(capfd, ["--python", str(no_package), "--results", str(results)])
    assert line.endswith("cannot import impact_eval: ModuleNotFoundError: No module named "
                         "impact_eval")
    assert _files(results) == before


def test_a_childs_refusal_is_its_own_line_and_exit_code(tmp_path, capfd) -> None:
    """The sweep refuses (exit 2, its one line): that line alone on stderr, exit 2, the table
    untouched; another exit code (1, a signal) is passed on the same way."""
    from impact_experiments.rerun_tables import main

    results = _results(tmp_path)
    before = _files(results)
    refusal = "impact-eval: error: invalid method 'impact'; valid choices: x"
    for sweep, code in ((f'echo "{refusal}" >&2; exit 2', 2), ("exit 1", 1),
                        ("kill -9 $$", 137)):
        python = _fake_python(tmp_path, sweep)
        assert main(["--python", str(python), "--results", str(results)]) == code
        err = capfd.readouterr().err.splitlines()
        assert err == ([refusal] if code == 2 else [])
        assert _files(results) == before


def test_a_sweep_that_writes_no_rows_keeps_the_table(tmp_path, capfd) -> None:
    """A sweep exiting 0 without an episodes.csv does not replace the table by nothing."""
    results = _results(tmp_path)
    before = _files(results)
    line = _refused(capfd, ["--python", str(_fake_python(tmp_path, "exit 0")),
                            "--results", str(results)])
    assert line == (f"rerun_tables: error: the sweep of t wrote no "
                    f"{results / '.rerun' / 't' / 'episodes.csv'}; {results / 't'} is kept")
    assert _files(results) == before


def test_to_version_reruns_a_table_into_its_twin_and_leaves_the_table(tmp_path, capfd) -> None:
    """issue 59: ``--to-version 2`` runs the table's command on -v2 into ``t_v2`` and records
    it; ``t`` stays byte for byte; a twin already in the manifest is skipped; a version the
    env does not register is one line before anything runs."""
    import json

    from impact_experiments.rerun_tables import main, version_args

    results = _results(tmp_path)
    manifest = json.loads((results / "manifest.json").read_text())
    manifest["tables"]["t"]["sweep_args"][1] = "IMPACT/Hammer-v1"
    (results / "manifest.json").write_text(json.dumps(manifest))
    assert version_args(["--env", "IMPACT/Hammer-v1", "--seed", "0"], 2) == [
        "--env", "IMPACT/Hammer-v2", "--seed", "0"]
    line = _refused(capfd, ["--to-version", "3", "--results", str(results),
                            "--python", str(_fake_python(tmp_path, "exit 0"))])
    assert line.endswith("IMPACT/Hammer-v1 has no registered version 3")
    before = _files(results / "t")
    # the fake sweep writes rows where --out points; the fake record adds the twin's entry
    sweep = ('if [ "$3" = "reproduce" ]; then python3 -c "import json,sys; p=sys.argv[1]; '
             "m=json.load(open(p)); m['tables']['t_v2']={'sweep_args': []}; "
             'json.dump(m, open(p, \'w\'))" ' + str(results / "manifest.json") + '; exit 0; fi\n'
             'for a in "$@"; do [ "$prev" = "--out" ] && out=$a; prev=$a; done\n'
             'echo "$@" > /dev/null; mkdir -p "$out" && echo "method\\nx" > "$out/episodes.csv"')
    python = _fake_python(tmp_path, sweep)
    assert main(["--to-version", "2", "t", "--python", str(python),
                 "--results", str(results)]) == 0
    out = capfd.readouterr().out
    assert "IMPACT/Hammer-v2" in out and (results / "t_v2" / "episodes.csv").is_file()
    assert _files(results / "t") == before
    assert main(["--to-version", "2", "t", "--python", str(python),
                 "--results", str(results)]) == 0
    assert "t_v2: already recorded, skipped" in capfd.readouterr().out
