"""``impact-eval``: success-vs-parameter sweeps of IMPACT methods, and ``report`` to redraw.

Exit codes: 0 success; 2 bad input (one-line message on stderr, no files created);
1 the sweep started but could not finish (rerun with ``--resume``).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from impact_control.errors import ImpactError
from impact_eval.sweep_command import (  # noqa: F401 - the sweep's names, re-exported
    PROG,
    QUICK_DEFAULTS,
    _Parser,
    crashed_cells,
    print_outputs,
    quick_methods,
    run_sweep_command,
    sweep_parser,
)


def report_parser() -> argparse.ArgumentParser:
    """Parser of ``impact-eval report DIR``."""
    p = _Parser(
        prog=f"{PROG} report",
        description="Rewrite summary.csv and plots/ of DIR from DIR/episodes.csv alone.",
    )
    p.add_argument("dir", type=Path, help="output directory of a sweep")
    return p


def run_report(argv: Sequence[str]) -> int:
    """``impact-eval report DIR``."""
    from impact_eval.report import write_report

    args = report_parser().parse_args(argv)
    summary, plots = write_report(args.dir)
    print(f"{PROG}: redrew the report of {args.dir}")
    print_outputs(args.dir, summary, plots)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Console entry point; returns the exit code."""
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        if argv and argv[0] == "report":
            return run_report(argv[1:])
        if argv and argv[0] == "reproduce":
            from impact_eval.reproduce import main as run_reproduce

            return run_reproduce(argv[1:])
        return run_sweep_command(argv)
    except ImpactError as exc:
        from impact_eval.sweep import SweepError

        print(f"{PROG}: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return 1 if isinstance(exc, SweepError) else 2
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted; rerun with --resume to continue", file=sys.stderr)
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
