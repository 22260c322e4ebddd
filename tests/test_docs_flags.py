"""Every command a docs page names exists and takes the options the page gives it, on every
page (README.md and every page under docs/; issues 57, 58). tests/test_docs_commands.py runs
README.md's and docs/eval.md's blocks; this test covers the rest without running anything long: each
``python -m impact_...`` module and ``impact-*`` entry point named in a shell block or an inline
code span must exist, and each ``--option`` written after it must appear in its ``--help``
(read in this process; a module without an argument parser may be given no option).
"""

from __future__ import annotations

import contextlib
import importlib
import io
import re
import runpy
import shlex
import sys
import warnings
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = (ROOT / "README.md", *sorted(p for p in (ROOT / "docs").rglob("*.md")
                                     if "plans" not in p.relative_to(ROOT / "docs").parts))
"""README.md and every page of the site (docs/ and its folders; docs/plans/ is not on it)."""
SCRIPTS: dict[str, str] = dict(re.findall(  # [project.scripts]; no tomllib on 3.10
    r'^(impact-[\w-]+) = "([\w.:]+)"$', (ROOT / "pyproject.toml").read_text(), re.M))
SHELL_FENCES = ("", "bash", "sh", "console", "shell")
INLINE = re.compile(r"`([^`\n]*(?:python -m impact|impact-)[^`\n]*)`")
PREFIXES = ("timeout", "time", "nohup", "env", "$")
OPTIONAL_MISSING = "optional extra not installed: "
"""A command of an extra this venv lacks is checked for existence only (its options where the
extra is installed, as in CI's robosuite venv)."""


@dataclass(frozen=True)
class Command:
    """One command as a page writes it: the page, the module or entry point, its arguments."""

    page: str
    program: str
    args: tuple[str, ...]


def shell_blocks(text: str) -> list[str]:
    """The text of every fenced shell block (a fence opened with another language is skipped
    whole, its closing fence included)."""
    blocks, lang, lines = [], None, []
    for line in text.splitlines():
        if line.startswith("```"):
            if lang is None:
                lang, lines = line[3:].strip(), []
            else:
                if lang in SHELL_FENCES:
                    blocks.append("\n".join(lines))
                lang = None
        elif lang is not None:
            lines.append(line)
    return blocks


def command_of(page: str, text: str) -> Command | None:
    """The project command in one shell command's text, else None."""
    try:
        toks = shlex.split(text, comments=True)
    except ValueError:
        return None
    while toks and (toks[0] in PREFIXES or toks[0].isdigit()
                    or ("=" in toks[0] and not toks[0].startswith("-"))):
        toks = toks[1:]
    if len(toks) >= 3 and toks[0].endswith("python") and toks[1] == "-m" \
            and toks[2].startswith("impact"):
        return Command(page, toks[2], tuple(toks[3:]))
    if toks and toks[0] in SCRIPTS:
        return Command(page, toks[0], tuple(toks[1:]))
    return None


def commands() -> list[Command]:
    found = []
    for path in PAGES:
        text, page = path.read_text(), str(path.relative_to(ROOT))
        pieces = [m.group(1) for m in INLINE.finditer(text)]
        for block in shell_blocks(text):
            pieces += [p for line in block.replace("\\\n", " ").splitlines()
                       for p in re.split(r"&&|\|\||;|\|", line)]
        found += [c for p in pieces if (c := command_of(page, p.strip()))]
    return found


def _module(program: str) -> str:
    return SCRIPTS[program].split(":")[0] if program in SCRIPTS else program


def module_files(module: str) -> list[Path]:
    """The source files ``python -m module`` runs (found without importing anything)."""
    base = ROOT / module.replace(".", "/")
    files = [base.with_suffix(".py"), base / "__main__.py"]
    return [f for f in files if f.is_file()]


def _takes_arguments(module: str) -> bool:
    """Whether ``module`` parses a command line (read from its source, and from the module a
    package's ``__main__`` takes its ``main`` from): a module that does not would run, not
    print its help."""
    source = "".join(f.read_text() for f in module_files(module))
    for target in re.findall(r"^from (impact_[\w.]+) import main$", source, re.M):
        source += "".join(f.read_text() for f in module_files(target))
    return any(word in source for word in ("parse_args", "argparse", "ArgumentParser"))


_HELP: dict[tuple[str, ...], str] = {}


def help_text(program: str, sub: tuple[str, ...] = ()) -> str:
    """``program [sub] --help``'s output, run in this process (cached)."""
    key = (program, *sub)
    if key not in _HELP:
        out, old = io.StringIO(), sys.argv
        sys.argv = [program, *sub, "--help"]
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()), \
                    warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)  # runpy: module already imported
                if program in SCRIPTS:
                    module, func = SCRIPTS[program].split(":")
                    getattr(importlib.import_module(module), func)()
                else:
                    runpy.run_module(program, run_name="__main__", alter_sys=False)
        except SystemExit:
            pass
        except ModuleNotFoundError as missing:  # an optional extra (robosuite) not installed
            if str(missing.name).startswith("impact"):
                raise
            out.write(f"{OPTIONAL_MISSING}{missing.name}")
        finally:
            sys.argv = old
        _HELP[key] = out.getvalue()
    return _HELP[key]


def unknown_options(cmd: Command) -> list[str]:
    """The ``--options`` of ``cmd`` its ``--help`` does not list."""
    options = [o.rstrip("],.;:)") for a in cmd.args if a.startswith("--")
               for o in a.split("=")[0].split("/") if len(o) > 2]
    if not options:
        return []
    if not _takes_arguments(_module(cmd.program)) and cmd.program not in SCRIPTS:
        return options
    top = help_text(cmd.program)
    if top.startswith(OPTIONAL_MISSING):
        return []
    text = top
    if cmd.args and re.fullmatch(r"[a-z][a-z_-]*", cmd.args[0]):  # a subcommand's own help
        sub_help = help_text(cmd.program, cmd.args[:1])
        text = sub_help if sub_help.startswith("usage:") and cmd.args[0] in sub_help else top
    return [o for o in options if not re.search(re.escape(o) + r"(?![\w-])", text)]


CASES = commands()


def test_pages_name_commands() -> None:
    assert len(CASES) > 100 and len({c.page for c in CASES}) > 8


@pytest.mark.parametrize("program", sorted({c.program for c in CASES}))
def test_every_named_command_exists(program: str) -> None:
    assert program in SCRIPTS or module_files(program), program


def test_every_option_a_page_gives_is_taken() -> None:
    wrong = [f"{c.page}: {c.program} {o}" for c in CASES for o in unknown_options(c)]
    assert wrong == []


def test_a_misspelt_option_is_caught() -> None:
    cmd = command_of("x.md", "impact-eval --env IMPACT/Hammer-v1 --episodez 3")
    assert cmd is not None and unknown_options(cmd) == ["--episodez"]
