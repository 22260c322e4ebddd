"""Every earlier layout of a run's record, read in one place (issue 57 item 1).

A run records what defines its rows once: ``identity.json`` (written before the first row) and
run.json's ``"identity"`` hold ``RunIdentity.to_json()``: the spec (``SweepSpec.to_json``)
with what ``prepare`` resolved from the env and the methods. Earlier layouts:

1. ``spec_format`` 1 (2026-11-27 to 2026-12-02): run.json held ``"spec"`` beside an
   ``"args"`` echo of the command line and the resolved keys (``param_name``,
   ``method_controllers``); ``identity.json`` was flat (``env``, ``seed``, ``param_name``, …).
2. Before the spec: run.json's ``"args"`` only (the parsed command line plus ``env``,
   ``methods``, ``values``, ``param_name``, …), and no ``identity.json``.

``identity_of`` turns any of them into the current layout; nothing else reads them.
"""

from __future__ import annotations

from impact_control.errors import InvalidArgumentError

SPEC_FORMAT = 2
"""Version of the identity's layout (``"spec_format"``): 2 since issue 57 (module docstring)."""
LEGACY_KEYS = ("env", "seed", "methods", "values", "episodes")
"""The flat keys without which a legacy record cannot be read (then ``--resume`` refuses)."""
_RESOLVED = ("param_name", "method_controllers", "policy_fingerprints")


def spec_of_flat(flat: dict) -> dict:
    """The spec (``SweepSpec.to_json``'s keys) of a flat legacy record: a ``spec_format`` 1
    identity.json or a run.json's ``"args"``. Keys added later default to the value runs had
    before them (no robot overrides, no bins, within the hardware limits)."""
    return {
        "env_id": flat["env"],
        "methods": list(flat["methods"]),
        "values": list(flat["values"]),
        "bin_highs": list(flat.get("bin_highs") or []),
        "episodes": flat["episodes"],
        "seed": flat["seed"],
        "param": flat.get("param"),
        "controller_overrides": list(flat.get("controller_overrides") or []),
        "robot_overrides": list(flat.get("robot_overrides") or []),
        "beyond_hardware_limits": bool(flat.get("beyond_hardware_limits", False)),
        "end_early": False,
    }


def identity_of(record: dict | None) -> dict | None:
    """The identity (current layout, ``RunIdentity.to_json``) in ``record``: an identity.json
    or a run.json of any layout; ``None`` when it holds none (a run.json without arguments).
    A record whose spec cannot be read is one line (``InvalidArgumentError``)."""
    if record is None:
        return None
    if "identity" in record and isinstance(record["identity"], dict):  # a current run.json
        return _checked(record["identity"])
    if record.get("spec_format") == SPEC_FORMAT and "spec" in record:  # a current identity
        return _checked(record)
    flat = record.get("args") if "args" in record else record
    if not isinstance(flat, dict) or not all(k in flat for k in LEGACY_KEYS):
        return None
    try:
        spec = record["spec"] if isinstance(record.get("spec"), dict) else spec_of_flat(flat)
    except (TypeError, ValueError) as exc:
        raise InvalidArgumentError(f"damaged run record ({exc}); restore run.json and "
                                   "identity.json or use another --out") from None
    return {"spec_format": SPEC_FORMAT, "spec": spec,
            **{k: flat[k] for k in _RESOLVED if k in flat}}


def _checked(identity: dict) -> dict:
    """``identity`` if its spec is an object, else one line."""
    if not isinstance(identity.get("spec"), dict):
        raise InvalidArgumentError("damaged run record ('spec' is not an object); restore "
                                   "run.json and identity.json or use another --out")
    return identity


def spec_json_of(run: dict, where: str = "run.json") -> dict:
    """The spec (``SweepSpec.to_json``'s keys) a run.json of any layout recorded; a run.json
    without one is one line naming ``where``."""
    identity = identity_of(run)
    spec = identity.get("spec") if identity else None
    if not isinstance(spec, dict):
        raise InvalidArgumentError(f"{where} records no sweep spec (neither 'identity', 'spec' "
                                   "nor 'args'); restore it")
    return spec
