"""The internal model stage: an online-trained MLP over a short state history that predicts the
slow external wrench, fed forward by the controller.

Modules: ``model.py`` (``InternalModel``: history, fast path, gate, replay, SGD, persistence),
``kernels.py`` (its buffer layouts and ``@njit`` steps), ``net.py`` (the network as NumPy
arrays, feature layout and the hand-written SGD step), ``gate.py`` (the surprise gate),
``replay.py``.
"""

from impact_control.internal_model.model import InternalModel, ModelSnapshot
from impact_control.internal_model.net import (
    FEATURE_DIM,
    FEATURE_NAMES,
    FEATURE_OFFSET,
    FEATURE_SCALE,
    OUTPUT_SCALE,
    build_network,
)

__all__ = [
    "FEATURE_DIM",
    "FEATURE_NAMES",
    "FEATURE_OFFSET",
    "FEATURE_SCALE",
    "OUTPUT_SCALE",
    "InternalModel",
    "ModelSnapshot",
    "build_network",
]
