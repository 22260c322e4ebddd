"""Where a sweep's time goes, read from py-spy samples of the sweep itself (issue 56 item 1).

``impact-bench --episode`` times the parts of one episode in a benchmark; this reads a real
table instead. Record the running sweep out of process, in files of a fixed length::

    py-spy record --pid PID --subprocesses -r 10 -d 1200 --format raw -o spy/0001.txt

then ``python -m impact_experiments.profile_split spy/*.txt --episodes N --wall-s W``. Each
sample of a worker's main thread (a stack through ``_worker_main``) counts for one part, the
first of ``PARTS`` whose frame is on its stack: rendering the cameras (``render`` in
``impact_envs/envs/pixels.py``), the policy (the ``act`` the rollout calls, any policy),
physics (``step`` in ``impact_envs/robot/sim.py``: raw ``mj_step``) and the rest (the 1 kHz
controller, the env's own work, resets and loading). Frames are matched by function name and
file, so py-spy's class-qualified names (``DiffusionPolicy.act``) and its older bare ones both
count. Idle samples are not recorded by py-spy, and the driver process and the workers' queue
threads are left out. With the table's episodes and wall time, the shares become seconds of
one worker per episode. Samples of which no named part matched are refused in one line: the
markers no longer name this code.
"""

from __future__ import annotations

import argparse
from collections import Counter
from pathlib import Path

PARTS = (("rendering", "render", "impact_envs/envs/pixels.py:"),
         ("policy", "act", "impact_eval/rollout.py:"),
         ("physics (mj_step)", "step", "impact_envs/robot/sim.py:"))
"""(part, function, file): a frame of that function in that file marks the part; for the
policy, a frame of that function called from that file (the rollout asking its policy)."""
REST = "controller, env and the rest"
WORKER_FRAME = "_worker_main ("
"""The frame of a sweep worker's main loop (``impact_eval/sweep.py``)."""


def _function(frame: str) -> str:
    """``DiffusionPolicy.act (path.py:12)`` -> ``act``."""
    return frame.partition(" (")[0].rpartition(".")[2]


def part_of(stack: str) -> str:
    """The part one sampled stack (py-spy raw, frames joined by ';', root first) counts for."""
    frames = stack.split(";")
    for name, function, where in PARTS:
        if name == "policy":
            if any(where in caller and _function(frame) == function
                   for caller, frame in zip(frames, frames[1:], strict=False)):
                return name
        elif any(where in frame and _function(frame) == function for frame in frames):
            return name
    return REST


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
    for name in (*(part for part, _, _ in PARTS), REST):
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
    for option, value in (("--episodes", args.episodes), ("--wall-s", args.wall_s),
                          ("--workers", args.workers)):
        if value is not None and value <= 0:
            parser.error(f"{option} {value}: valid: a number above 0")
    missing = [str(p) for p in args.files if not p.is_file()]
    if missing:
        parser.error(f"no such file: {', '.join(missing)}; valid: py-spy --format raw output")
    counts = count_samples(args.files)
    if not counts:
        parser.error(f"no sample of a sweep worker ({WORKER_FRAME.strip(' (')}) in the files; "
                     "valid: py-spy record --subprocesses on the impact-eval process")
    if sum(counts.values()) == counts[REST]:
        parser.error("no sample matched a named part (rendering, policy, physics): the markers "
                     "in PARTS no longer name this code; valid: py-spy samples of impact-eval")
    print(split_table(counts, args.episodes, args.wall_s, args.workers), end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
