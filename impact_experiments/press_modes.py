"""What both press scenarios share (``press``: a plate pressed at an angle; ``press_setdown``: a
load set down onto a table): the controller of each mode, the trace choices and the record of
the robot the results ran on."""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

from impact_control.config import ControllerConfig
from impact_control.errors import InvalidArgumentError
from impact_control.presets import preset_config

TRACES = ("failing", "impact", "all", "none")
"""``--traces``: whose set-down traces are written (``press_setdown.wants_trace``)."""


def mode_controller(mode: str) -> tuple[str, ControllerConfig]:
    """(controller mode, config) of a press mode: its preset as shipped (``authors_sim``
    without an estimator argument: it runs the authors' observer)."""
    base = preset_config(mode if mode in ("paper", "authors_sim", "lift_watch", "keep_carried")
                         else "default")
    if mode == "impact_unguarded":
        base = replace(base, guard=replace(base.guard, enabled=False))
    return ("impedance" if mode == "impedance" else "impact"), base


def check_robot_record(out: Path, robot_set: Sequence[str]) -> None:
    """Keep ``robot_set`` in ``out/robot.json``; InvalidArgumentError (one line) when ``out``
    holds results of another robot (no file: the ideal robot, ``[]``)."""
    path = out / "robot.json"
    had = json.loads(path.read_text())["robot_set"] if path.exists() else []
    if list(had) != list(robot_set) and (out / "setdown.csv").exists():
        raise InvalidArgumentError(
            f"{out} holds set-downs with --robot-set {had or 'none (ideal)'}, not "
            f"{list(robot_set) or 'none (ideal)'}; valid: the same --robot-set, or another --out")
    path.write_text(json.dumps({"robot_set": list(robot_set)}) + "\n")
