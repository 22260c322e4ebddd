"""Declares torchvision's missing op schemas when (and only when) ``torchvision`` is imported.

``tests/learn/lerobot_venv.sh`` copies this file into the LeRobot virtualenv's site-packages
as ``impact_torchvision_hook.py``, with a ``.pth`` file importing it at startup, so that
LeRobot's own commands (``lerobot-eval``), which import torchvision before any plugin loads,
work beside the CPU torch (``impact_learn/lerobot_compat.py`` says why the import fails
otherwise). At startup it only puts a finder in ``sys.meta_path`` (standard library only);
the first ``import torchvision`` removes it and runs ``define_missing_torchvision_ops``.
"""

from __future__ import annotations

import importlib.abc
import sys
from collections.abc import Sequence
from importlib.machinery import ModuleSpec
from types import ModuleType


class TorchvisionOpsHook(importlib.abc.MetaPathFinder):
    """Finds nothing itself; before the first ``torchvision`` import it declares the ops."""

    def find_spec(self, fullname: str, path: Sequence[str] | None = None,
                  target: ModuleType | None = None) -> ModuleSpec | None:
        if fullname == "torchvision":
            sys.meta_path.remove(self)
            from impact_learn.lerobot_compat import define_missing_torchvision_ops

            define_missing_torchvision_ops()
        return None


if not any(isinstance(f, TorchvisionOpsHook) for f in sys.meta_path):
    sys.meta_path.insert(0, TorchvisionOpsHook())
