"""Compiling a scene: the package's own, or one anywhere that includes the robot by name."""

from __future__ import annotations

from pathlib import Path

import mujoco

from impact_control.dynamics import ROBOT_XML
from impact_control.errors import InvalidArgumentError

ASSETS = Path(__file__).resolve().parent.parent / "assets"
"""The package's MuJoCo files: common.xml and the task scenes (the robot, fr3_hand.xml, is
``impact_control``'s: ``ROBOT_XML``)."""
SCENE_FILE_TYPES = (".xml", ".stl", ".obj", ".msh", ".png")
"""Files a scene outside ``assets/`` may reference by name (``load_scene``)."""

def load_scene(scene_xml: str | Path) -> mujoco.MjModel:
    """Compile a scene: a file name in the package's ``assets/``, or a path anywhere whose
    ``<include file="fr3_hand.xml"/>`` / ``"common.xml"`` (and any other file name) resolve
    to the scene's own directory first, then to ``assets/``, then to the robot's file
    (docs/adding_a_task.md)."""
    path = Path(scene_xml)
    if not path.is_absolute():
        path = ASSETS / path
    try:
        text = path.read_text()
    except OSError as exc:
        raise InvalidArgumentError(f"cannot read scene {path}: {exc}") from None
    files = {ROBOT_XML.name: ROBOT_XML.read_bytes()}
    for folder in (ASSETS, path.parent):  # the scene's own files win
        files.update({p.name: p.read_bytes() for p in folder.iterdir()
                      if p.is_file() and p.suffix.lower() in SCENE_FILE_TYPES})
    return mujoco.MjModel.from_xml_string(text, assets=files)
