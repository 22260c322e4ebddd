"""A row-defining sweep option is one declaration plus its use in the worker (issue 57 item 1;
docs/eval.md, "An option is declared once").

On a copy of the packages, one field is added to ``SweepSpec`` (``--param-scale F``: each
episode resets its parameter at F times the cell's value) and one line of the worker uses it
(``SweepConfig.job``). Nothing else is edited: the flag, its help and parsing, run.json's and
identity.json's record, ``reproduce``'s arguments and ``--resume``'s refusal all follow. The
sweep runs on the fake env (milliseconds per episode) in one subprocess on the copy.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
PACKAGES = ("impact_control", "impact_envs", "impact_eval", "impact_learn", "impact_lerobot")

DECLARATION = '''
    param_scale: float = option(Value(
        "--param-scale", "reset each episode's parameter at F times its cell's value",
        type=float, parse=float, metavar="F"), default=1.0)
    """A sensitivity check: the factor on each episode's reset value (tests only)."""
'''
ANCHOR = '    """Base seed of the paired episode seeds (``grid.episode_seed``)."""\n'
USE = ("            return EpisodeJob(value, seed, episode)",
       "            return EpisodeJob(value, seed, episode, value * spec.param_scale)")

SCRIPT = r'''
import json, sys
from pathlib import Path
import impact_eval.spec
from impact_control.errors import ImpactError
from impact_eval.cli import main
from impact_eval.reproduce_manifest import sweep_argv

assert impact_eval.spec.__file__.startswith(sys.argv[1]), impact_eval.spec.__file__
out = Path(sys.argv[2])
base = ["--env", "fixtures.eval_fake:ImpactTest/Fake-v0", "--method", "fake_fast",
        "--masses", "1,3", "--episodes", "2", "--workers", "1", "--envs-per-worker", "2"]
assert main([*base, "--param-scale", "2", "--out", str(out / "scaled")]) == 0
assert main([*base, "--out", str(out / "plain")]) == 0
run = json.loads((out / "scaled" / "run.json").read_text())
identity = json.loads((out / "scaled" / "identity.json").read_text())
print("RECORDED", run["identity"]["spec"]["param_scale"], identity["spec"]["param_scale"])
print("ARGV", json.dumps(sweep_argv(run)))
print("RESUME", main([*base, "--param-scale", "3", "--resume", "--out", str(out / "scaled")]))
'''


def _copy(tmp: Path) -> Path:
    root = tmp / "copy"
    for name in PACKAGES:
        shutil.copytree(REPO / name, root / name, ignore=shutil.ignore_patterns(
            "__pycache__", "checkpoints", "*.nbi", "*.nbc"))
    shutil.copytree(REPO / "tests" / "fixtures", root / "fixtures",
                    ignore=shutil.ignore_patterns("__pycache__"))
    spec = root / "impact_eval" / "spec.py"
    text = spec.read_text()
    assert text.count(ANCHOR) == 1
    spec.write_text(text.replace(ANCHOR, ANCHOR + DECLARATION))  # the one declaration
    worker = root / "impact_eval" / "sweep_config.py"
    text = worker.read_text()
    assert text.count(USE[0]) == 1
    worker.write_text(text.replace(*USE))  # its use in the worker
    return root


def test_a_new_row_defining_option_is_one_declaration(tmp_path: Path) -> None:
    import json

    import pandas as pd

    root = _copy(tmp_path)
    env = {**os.environ, "PYTHONPATH": str(root), "MUJOCO_GL": "egl"}
    done = subprocess.run([sys.executable, "-c", SCRIPT, str(root), str(tmp_path)], env=env,
                          capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-3000:]
    lines = dict(line.split(" ", 1) for line in done.stdout.splitlines()
                 if line.split(" ", 1)[0] in ("RECORDED", "ARGV", "RESUME"))
    assert lines["RECORDED"] == "2.0 2.0"  # run.json and identity.json, from the field
    argv = json.loads(lines["ARGV"])  # what reproduce reruns
    assert argv[argv.index("--param-scale") + 1] == "2.0"
    assert lines["RESUME"] == "2"  # another value: refused in one line, nothing run
    assert "cannot resume: param_scale was 2.0" in done.stderr
    scaled = pd.read_csv(tmp_path / "scaled" / "episodes.csv")
    plain = pd.read_csv(tmp_path / "plain" / "episodes.csv")
    assert (scaled["drawn_mass_kg"] == 2 * scaled["param_value"]).all()  # the worker used it
    assert (plain["drawn_mass_kg"] == plain["param_value"]).all()
    assert len(scaled) == len(plain) == 4
