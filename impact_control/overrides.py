"""Command-line overrides of a ``ControllerConfig``: ``SECTION.FIELD=VALUE``.

For ablations from the command line (``impact-eval --controller-set``,
``impact_experiments.trace``)::

    internal_model.slow_rate_max=1.5
    slow_wrench.rate_force_per_s=20
    impedance.stiffness_translational_n_per_m=800,800,800

The value is parsed by the type of the field's default (float, int, bool, str, a
comma-separated tuple; ``none`` or a float where the default is None); the dataclass's own
validation then runs. Unknown sections or fields
and malformed values are one-line ``InvalidArgumentError``s naming the valid choices.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

from impact_control.config import ControllerConfig
from impact_control.errors import InvalidArgumentError

_TRUE, _FALSE = ("1", "true", "yes", "on"), ("0", "false", "no", "off")


def _parse_value(key: str, text: str, default: object, optional: bool = False) -> object:
    """``text`` converted to the type of ``default``; ``none`` is None where the field is
    optional (``float | None``) whatever its current value."""
    try:
        if default is None or (optional and text.lower() == "none"):
            return None if text.lower() == "none" else float(text)
        if isinstance(default, bool):
            if text.lower() not in _TRUE + _FALSE:
                raise ValueError
            return text.lower() in _TRUE
        if isinstance(default, tuple):
            kind = type(default[0]) if default else float
            return tuple(kind(item) for item in text.split(","))
        return type(default)(text)
    except ValueError:
        kind = "comma-separated numbers" if isinstance(default, tuple) else type(default).__name__
        raise InvalidArgumentError(f"invalid value {text!r} for {key}; expected {kind}") from None


def _split(item: str) -> tuple[str, str, str]:
    """``"section.field=value"`` -> (section, field, value)."""
    key, sep, value = item.partition("=")
    section, dot, name = key.strip().partition(".")
    if not sep or not dot or not section or not name or not value.strip():
        raise InvalidArgumentError(
            f"malformed controller override {item!r}; expected SECTION.FIELD=VALUE, "
            "e.g. internal_model.slow_rate_max=1.5"
        )
    return section, name.strip(), value.strip()


def apply_overrides(config: ControllerConfig, items: Sequence[str]) -> ControllerConfig:
    """``config`` with each ``SECTION.FIELD=VALUE`` of ``items`` applied (left to right)."""
    sections = {
        f.name
        for f in dataclasses.fields(config)
        if dataclasses.is_dataclass(getattr(config, f.name))
    }
    for item in items:
        section, name, text = _split(item)
        if section not in sections:
            raise InvalidArgumentError(
                f"unknown controller config section {section!r}; valid: {sorted(sections)}"
            )
        part = getattr(config, section)
        fields = {f.name: f for f in dataclasses.fields(part)}
        if name not in fields:
            raise InvalidArgumentError(
                f"unknown field {name!r} of controller config section {section!r}; "
                f"valid: {list(fields)}"
            )
        optional = "None" in str(fields[name].type)
        value = _parse_value(f"{section}.{name}", text, getattr(part, name), optional)
        part = dataclasses.replace(part, **{name: value})
        config = dataclasses.replace(config, **{section: part})
    return config
