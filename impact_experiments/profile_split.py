"""Where a sweep's time goes, read from py-spy samples of the sweep itself (issue 56 item 1).

``impact-bench --episode`` times the parts of one episode in a benchmark; this reads a real
table instead. Record the running sweep out of process, in files of a fixed length::

    py-spy record --pid PID --subprocesses -r 10 -d 1200 --format raw -o spy/0001.txt

then ``python -m impact_experiments.profile_split spy/*.txt --episodes N --wall-s W``. Each
sample of a worker's main thread (a stack through ``_worker_main``) counts for one part, the
first of ``PARTS`` whose frame is on its stack: rendering the cameras, the policy's ``act``,
physics (``FrankaSim.step``: raw ``mj_step``) and the rest (the 1 kHz controller, the env's
own work, resets and loading). Idle samples are not recorded by py-spy, and the driver
process and the workers' queue threads are left out. With the table's episodes and wall
time, the shares become seconds of one worker per episode.
"""

from __future__ import annotations

import argparse
from collections import Counter
from pathlib import Path

PARTS = (("rendering", "PixelObservations.render ("), ("policy", "Policy.act ("),
         ("physics (mj_step)", "FrankaSim.step ("), ("controller, env and the rest", ""))
"""(part, a frame that marks it), in the order a stack is matched; "" matches every stack."""
WORKER_FRAME = "_worker_main ("
"""The frame of a sweep worker's main loop (``impact_eval/sweep.py``)."""


def part_of(stack: str) -> str:
    """The part one sampled stack (py-spy raw, frames joined by ';') counts for."""
    return next(name for name, frame in PARTS if frame in stack)


def count_samples(paths: list[Path]) -> Counter[str]:
    """Samples per part over py-spy raw files (``stack count`` per line), workers only."""
    counts: Counter[str] = Counter()
    for path in paths:
        for line in path.read_text().splitlines():
            stack, _, n = line.rpartition(" ")
            if WORKER_FRAME in stack and n.isdigit():
                counts[part_of(stack)] += int(n)
    return counts


def split_table(counts: Counter[str], episodes: int | None, wall_s: float | None,
                workers: int) -> str:
    """A markdown table: each part's samples and share and, given the table's episodes and
    wall time, its worker-seconds per episode."""
    total = sum(counts.values())
    per_episode = wall_s * workers / episodes if episodes and wall_s else None
    head = "| part | samples | share |" + (" s / episode |" if per_episode else "")
    lines = [head, "|---|---|---|" + ("---|" if per_episode else "")]
    for name, _ in PARTS:
        share = counts[name] / total
        cells = f"| {name} | {counts[name]} | {share:.1%} |"
        lines.append(cells + (f" {share * per_episode:.2f} |" if per_episode else ""))
    lines.append(f"| all | {total} | 100% |" + (f" {per_episode:.2f} |" if per_episode else ""))
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", type=Path, nargs="+", help="py-spy raw files of the sweep")
    parser.add_argument("--episodes", type=int, help="the table's episodes")
    parser.add_argument("--wall-s", type=float, help="the table's wall time [s]")
    parser.add_argument("--workers", type=int, default=2, help="the sweep's workers")
    args = parser.parse_args(argv)
    missing = [str(p) for p in args.files if not p.is_file()]
    if missing:
        parser.error(f"no such file: {', '.join(missing)}; valid: py-spy --format raw output")
    counts = count_samples(args.files)
    if not counts:
        parser.error(f"no sample of a sweep worker ({WORKER_FRAME.strip(' (')}) in the files; "
                     "valid: py-spy record --subprocesses on the impact-eval process")
    print(split_table(counts, args.episodes, args.wall_s, args.workers), end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
