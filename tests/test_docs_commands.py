"""The command blocks a new user copies from README.md, docs/index.md and docs/eval.md run and
do what their comments say. Each fenced ``bash``/``python`` block is classified below: run as
written, run after documented substitutions (fragments made runnable, long sweeps made short),
or skipped with the reason docs/eval.md ("Command blocks under test") lists. A block added to
any of these files without a classification fails ``test_every_block_is_classified``.

Blocks run in a fresh interpreter in a temporary folder (relative ``results/...`` paths land
there), with ``MUJOCO_GL``, ``DISPLAY`` and ``WAYLAND_DISPLAY`` unset, as on a fresh machine
without a display.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ("README.md", "docs/index.md", "docs/eval.md")
FENCE = re.compile(r"^```(bash|python)\n(.*?)^```", re.S | re.M)


def blocks() -> list[tuple[str, str, str]]:
    """``(file, language, text)`` of every fenced bash/python block, in order."""
    return [(doc, m.group(1), m.group(2)) for doc in DOCS
            for m in FENCE.finditer((ROOT / doc).read_text())]


@dataclass(frozen=True)
class Plan:
    """How one block is run: the text it must contain (to find it), substitutions (each must
    apply), what its output must contain, or a reason to skip it."""

    key: str
    substitutions: tuple[tuple[str, str], ...] = ()
    expect: tuple[str, ...] = ()
    slow: bool = False
    skip: str = ""
    drop_optional: bool = False
    """Remove ``[...]`` groups (a synopsis's optional arguments) before running."""
    check: str = ""
    """Python lines appended to a python block (assertions on its variables)."""
    extra: tuple[str, ...] = field(default=())


SYNOPSIS = "impact-eval --env IMPACT/Hammer-v2 \\\n    --method scripted,scripted_impact,vanilla_dp"

PLANS = (
    Plan('pip install -e ".[bench]" && impact-eval --quick --out results/quickstart',
         substitutions=(('pip install torch==2.13.0 && pip install -e ".[bench]" && ', ""),),
         expect=("impact-eval: 80 episodes run",), slow=True),
    Plan('pip install -e ".[dev]" && python -m pytest -n 2',
         skip="installs packages and runs the whole suite, which holds this test"),
    Plan('print(info["success_once"], load)',
         check="assert info['success_once'] and 39.0 < load[2] < 59.0, load  # m g = 49 N"),
    Plan('print(obs["overview_rgb"].shape, obs["wrist_rgb"].shape)',
         expect=("(96, 96, 3) (96, 96, 3)",)),
    Plan("--video 1 --out results/video", slow=True,
         expect=("impact-eval: 1 episodes run",),
         extra=("results/video/videos/scripted_impact/object_mass=5.0_ep000.mp4",)),
    Plan(SYNOPSIS, drop_optional=True, slow=True,
         substitutions=(("--masses 0.1:10:0.5 --episodes 20", "--masses 2.5 --episodes 1"),),
         expect=("impact-eval: 5 episodes run", "impact-eval: redrew the report of "
                 "results/hammer")),
    Plan("table = impact_eval.evaluate(my_policy",
         substitutions=(("import impact_eval\n", "import impact_eval\nfrom impact_envs.policies"
                         ".experts import make_expert\nmy_policy = make_expert('IMPACT/Hammer-"
                         "v2')\n"), ("[0.5, 2.0, 5.0]", "[2.0]"), ("episodes=20", "episodes=1")),
         check="assert len(table) == 1 and table['method'].tolist() == ['mine']"),
)


def plan_of(text: str) -> list[Plan]:
    return [p for p in PLANS if p.key in text]


def without_optional(text: str) -> str:
    """The synopsis without its ``[...]`` groups (nested ones included), each command on one
    line."""
    text = text.replace("\\\n", " ")
    while True:
        shorter = re.sub(r"[ \t]*\[[^\[\]\n]*\]", "", text)
        if shorter == text:
            return re.sub(r"[ \t]+", " ", text)
        text = shorter


def runnable(plan: Plan, text: str) -> str:
    for old, new in plan.substitutions:
        assert old in text, f"substitution {old!r} no longer applies to {plan.key!r}"
        text = text.replace(old, new)
    if plan.drop_optional:
        text = without_optional(text)
    return text + ("\n" + plan.check + "\n" if plan.check else "")


def test_every_block_is_classified() -> None:
    """One plan per block (a new or rewritten block needs a line in PLANS), and no stale plan."""
    found = blocks()
    assert len(found) >= 7
    for doc, _, text in found:
        keys = {p.key for p in plan_of(text)}
        assert len(keys) == 1, f"{doc}: classify this block in tests/test_docs_commands.py:\n" \
                               f"{text[:200]}"
    for plan in PLANS:
        assert any(plan.key in text for _, _, text in found), f"stale plan {plan.key!r}"


def test_skipped_blocks_are_listed_in_the_docs() -> None:
    eval_md = (ROOT / "docs/eval.md").read_text()
    assert "Command blocks under test" in eval_md
    assert "python -m pytest" in eval_md.split("Command blocks under test")[1][:2500]


def _environ() -> dict[str, str]:
    environ = {k: v for k, v in os.environ.items()
               if k not in ("MUJOCO_GL", "DISPLAY", "WAYLAND_DISPLAY", "PYOPENGL_PLATFORM")}
    environ["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), environ["PATH"]])
    return environ


def _cases() -> list[object]:
    cases = []
    for doc, language, text in blocks():
        for plan in plan_of(text):
            if plan.skip:
                continue
            name = f"{doc}:{plan.key[:40]}"
            marks = [pytest.mark.slow] if plan.slow else []
            cases.append(pytest.param(language, runnable(plan, text), plan, id=name,
                                      marks=marks))
    return cases


@pytest.mark.parametrize("language,text,plan", _cases())
def test_block_runs(language: str, text: str, plan: Plan, tmp_path: Path) -> None:
    command = ["bash", "-euo", "pipefail", "-c", text] if language == "bash" else [
        sys.executable, "-c", text]
    done = subprocess.run(command, cwd=tmp_path, env=_environ(), capture_output=True,
                          text=True, timeout=1800)
    output = done.stdout + done.stderr
    assert done.returncode == 0, output[-3000:]
    for part in plan.expect:
        assert part in output, output[-3000:]
    for path in plan.extra:
        assert (tmp_path / path).is_file(), path
