"""A sweep option, declared once: the command-line form of a ``SweepSpec`` or ``RunOptions``
field lives in that field's metadata (``option(...)``), and the parser, ``from_cli``,
``to_argv`` and the resume check are generated from it (issue 57 item 1).

A declaration says:

- how the value is given (``Value``: ``--flag VALUE``; ``Repeated``: ``--flag V`` repeatable;
  ``Switch``: ``--flag``), its help, and the parser for the text (``parse``);
- how it is written back (``Value.show``; ``to_argv``);
- ``resume``: how ``--resume`` treats a recorded run whose value differs (``"same"``: refused;
  ``"grow"``: ``--extend`` may add to it; ``"free"``: not compared, because the rows do not
  depend on it or a resolved value is compared instead).

A row-defining option is then one field with its ``option(...)`` plus its use in the worker
(``tests/eval/test_adding_a_sweep_option.py`` proves it on a copy of the package).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from dataclasses import MISSING, Field, dataclass, field, fields
from typing import Any

RESUME_RULES = ("same", "grow", "free")
"""How ``--resume`` treats a field's recorded value (module docstring)."""


@dataclass(frozen=True)
class Value:
    """``--flag VALUE``: one value, converted by argparse's ``type`` (``int``: ``--episodes x``
    is argparse's one-line error) and then by ``parse`` where the field needs more (the method
    list; its errors are the field's own one-line ``InvalidArgumentError`` s)."""

    flag: str
    help: str | Callable[[], str]
    parse: Callable[[Any], Any] | None = None
    """None: the value as argparse gave it."""
    show: Callable[[Any], str] = str
    metavar: str | None = None
    type: Callable[[str], Any] | None = None
    """argparse's own conversion (None: the text)."""
    cli_default: Any = None
    """The parser's default where it differs from the field's (None: absent)."""


@dataclass(frozen=True)
class Repeated:
    """``--flag VALUE``, repeatable: a tuple of strings in the order given."""

    flag: str
    help: str
    metavar: str | None = None


@dataclass(frozen=True)
class Switch:
    """``--flag``: True when given."""

    flag: str
    help: str


Form = Value | Repeated | Switch


@dataclass(frozen=True)
class Option:
    """A field's command-line form and resume rule (the metadata ``option`` stores)."""

    form: Form | None
    """None: not an option of its own (a composite option fills it, e.g. the grid)."""
    resume: str = "same"

    @property
    def dest(self) -> str | None:
        return None if self.form is None else self.form.flag.lstrip("-").replace("-", "_")


def option(form: Form | None, default: Any = MISSING, resume: str = "same",
           default_factory: Any = MISSING) -> Any:
    """A dataclass field declared with its command-line form (module docstring)."""
    if resume not in RESUME_RULES:
        raise ValueError(f"resume={resume!r}; valid: {', '.join(RESUME_RULES)}")
    meta = {"option": Option(form, resume)}
    if default_factory is not MISSING:
        return field(default_factory=default_factory, metadata=meta)
    return field(default=default, metadata=meta)


def declared(cls: type) -> list[tuple[Field, Option]]:
    """The fields of dataclass ``cls`` that carry an ``option`` declaration, in order."""
    return [(f, f.metadata["option"]) for f in fields(cls) if "option" in f.metadata]


def add_arguments(parser: argparse.ArgumentParser, cls: type) -> None:
    """Add every declared option of ``cls`` to ``parser`` (defaults: None unless declared, so
    that ``from_namespace`` leaves absent options to the dataclass's own defaults)."""
    for _, opt in declared(cls):
        form = opt.form
        if isinstance(form, Value):
            help_text = form.help() if callable(form.help) else form.help
            parser.add_argument(form.flag, dest=opt.dest, type=form.type, metavar=form.metavar,
                                default=form.cli_default, help=help_text)
        elif isinstance(form, Repeated):
            parser.add_argument(form.flag, dest=opt.dest, action="append", default=None,
                                metavar=form.metavar, help=form.help)
        elif isinstance(form, Switch):
            parser.add_argument(form.flag, dest=opt.dest, action="store_true", help=form.help)


def from_namespace(cls: type, namespace: argparse.Namespace) -> dict[str, Any]:
    """Keyword arguments of ``cls`` from a parsed namespace: each given option parsed by its
    declaration; an absent one is left to the field's default."""
    out: dict[str, Any] = {}
    for f, opt in declared(cls):
        if opt.dest is None:
            continue
        given = getattr(namespace, opt.dest, None)
        if given is None or given is False:
            continue
        form = opt.form
        if isinstance(form, Value):
            out[f.name] = given if form.parse is None else form.parse(given)
        else:
            out[f.name] = tuple(given) if isinstance(form, Repeated) else True
    return out


def to_argv(instance: object) -> list[str]:
    """The command-line arguments that give ``instance``'s declared options, in declaration
    order (an unset one, None, empty or False, is left out)."""
    argv: list[str] = []
    for f, opt in declared(type(instance)):
        value, form = getattr(instance, f.name), opt.form
        if form is None or value is None or value is False or value == ():
            continue
        if isinstance(form, Value):
            argv += [form.flag, form.show(value)]
        elif isinstance(form, Repeated):
            for item in value:
                argv += [form.flag, item]
        else:
            argv.append(form.flag)
    return argv
