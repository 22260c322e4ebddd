"""``python -m impact_eval`` runs the ``impact-eval`` CLI."""

from impact_eval.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
