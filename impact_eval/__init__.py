"""impact-eval: paired-seed parameter sweeps, metrics, plots and reports for IMPACT methods.

Entry points: ``impact-eval`` (:func:`impact_eval.cli.main`) and, from Python,
:func:`impact_eval.evaluate` for a policy object; see docs/eval.md. Submodules import their
heavy dependencies (torch, pandas, Matplotlib) lazily; ``impact_envs`` is imported first, so
that its ``_gl`` picks MuJoCo's headless GL backend before anything loads mujoco.
"""

from __future__ import annotations

from impact_envs import _gl  # noqa: F401 - first: the headless GL backend before mujoco loads

__all__ = ["evaluate", "main"]


def main() -> int:
    """Run the ``impact-eval`` CLI (same as the console script)."""
    from impact_eval.cli import main as cli_main

    return cli_main()


def evaluate(*args, **kwargs):  # noqa: ANN002, ANN003, ANN201 - documented in impact_eval.api
    """``impact_eval.api.evaluate`` (imported on first use)."""
    from impact_eval.api import evaluate as run

    return run(*args, **kwargs)
