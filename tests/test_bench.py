"""impact-bench refuses bad input with one line before running anything."""

from __future__ import annotations

import pytest

from impact_eval.bench import main


@pytest.mark.parametrize("args, message", [
    (["--steps", "0"], "need --steps >= 2"),
    (["--repeat", "0"], "--repeat >= 1"),
    (["--mass", "nan"], "object_mass=nan out of range"),
    (["--mass", "-1"], "object_mass=-1.0 out of range"),
])
def test_bad_input_is_one_line_exit_2(args, message, capsys):
    with pytest.raises(SystemExit) as exc:
        main(args)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("impact-bench: error:") and message in err
