"""``impact-train --resume``: the flags that define a run must agree with the run.

A run is defined by its ``DiffusionConfig`` (``--config``, ``--batch-size``, ``--seed``), its
data (checked by content in ``train._check_same_run``) and its held-out split
(``--val-fraction``). On ``--resume`` each of these flags that is given must agree with the
run's value (one-line error naming the flag and both values, nothing written); a flag left out
takes the run's value. ``--steps`` (with its own rule), ``--checkpoint-every``, ``--val-every``,
``--threads``, ``--no-progress`` and the path of ``--data`` may change.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from impact_control.errors import InvalidArgumentError
from impact_envs.policies.diffusion.config import DiffusionConfig
from impact_learn.train_state import STATE_FILE, find_train_state


def check_resume_flags(args: argparse.Namespace, cfg: DiffusionConfig) -> dict[str, Any]:
    """Refuse ``impact-train --resume`` flags that differ from the run in ``args.out``;
    returns the run's recorded info (empty when there is no run to resume)."""
    out = Path(args.out)
    ckpt = find_train_state(out / "train_state")
    if ckpt is None:
        return {}
    run_cfg = DiffusionConfig.from_json(out / "config.json")
    given: list[tuple[str, str, object]] = []
    if args.config:
        fields = json.loads(Path(args.config).read_text())  # parsed before: a JSON object
        file_cfg = DiffusionConfig.from_json(args.config)
        given += [(f"--config {args.config}", key, getattr(file_cfg, key)) for key in fields]
    for flag, key in (("--batch-size", "batch_size"), ("--seed", "seed")):
        if getattr(args, key) is not None:
            given.append((flag, key, getattr(cfg, key)))
    for flag, key, value in given:
        if value != getattr(run_cfg, key):
            raise InvalidArgumentError(
                f"{flag} sets {key} {value!r}, but the run in {out} has {key} "
                f"{getattr(run_cfg, key)!r}; a resumed run keeps its settings: leave "
                f"{flag.split()[0]} out or use a new --out")
    try:
        info = json.loads((ckpt / STATE_FILE).read_text()).get("info", {})
    except (OSError, ValueError, AttributeError):
        info = {}  # a damaged train_state is reported when it is loaded
    return info if isinstance(info, dict) else {}
