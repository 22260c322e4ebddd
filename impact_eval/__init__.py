"""impact-eval: paired-seed parameter sweeps, metrics, plots and reports for IMPACT methods.

Entry point: ``impact-eval`` (:func:`impact_eval.cli.main`); see docs/eval.md. Submodules import
their heavy dependencies lazily, so ``import impact_eval`` is cheap.
"""

from __future__ import annotations

__all__ = ["main"]


def main() -> int:
    """Run the ``impact-eval`` CLI (same as the console script)."""
    from impact_eval.cli import main as cli_main

    return cli_main()
