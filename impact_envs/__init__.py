"""IMPACT: Gymnasium environments and the internal-model predictive controller.

Importing this package registers the environments, e.g. ``gym.make("IMPACT/Hammer-v0")``.
"""

from __future__ import annotations

__version__ = "0.1.0"
