"""Running lerobot 0.4.4 beside torch 2.13 (CPU), as ``tests/learn/lerobot_venv.sh`` installs it.

torchvision's PyPI wheel for torch 2.13 is built against CUDA torch; with the CPU torch its C
ops do not load, and ``import torchvision`` (which LeRobot's dataset and policy code does) fails
registering fake kernels for ``nms``/``qnms``. ``define_missing_torchvision_ops`` declares those
two schemas so the import works; nothing is declared when the ops load (docs/lerobot.md).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import torch

_LIBRARIES: list = []
"""The declared op library, kept alive for the process."""


def define_missing_torchvision_ops() -> None:
    """Declare torchvision's ``nms``/``qnms`` schemas when its C ops cannot load (idempotent)."""
    spec = importlib.util.find_spec("torchvision")
    if spec is None or spec.origin is None or _LIBRARIES:
        return
    try:
        torch.ops.load_library(str(Path(spec.origin).parent / "_C.so"))
    except OSError:
        lib = torch.library.Library("torchvision", "DEF")  # noqa: TOR901
        for op in ("nms", "qnms"):
            lib.define(f"{op}(Tensor dets, Tensor scores, float iou_threshold) -> Tensor")
        _LIBRARIES.append(lib)
