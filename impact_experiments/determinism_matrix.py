"""Run one sweep under every execution setting and compare the ``episodes.csv`` bytes.

Run ``python -m impact_experiments.determinism_matrix --out /tmp/det_matrix``.

The sweep (default: Hammer, ``vanilla_dp, augmented_dp, impact, impact_warm``, 0.2, 5 and 10 kg,
where the 10 kg episodes run long, 5 episodes per cell) runs as a fresh ``impact-eval`` process
per setting: ``--workers 2`` twice in a row, ``--workers 1``, ``--envs-per-worker 1``,
``--executor ray`` (skipped with a note where Ray is not installed) and one run SIGKILLed after
its first ``--kill-after`` rows, then resumed with ``--resume --workers 1 --envs-per-worker 2``
(so the resumed part is also regrouped). It prints the sha256 of each run's file, writes them
to ``OUT/determinism_matrix.json`` and exits 1 unless all are equal.
"""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
import time
from pathlib import Path

from impact_control.cli import OneLineParser

SWEEP = ["--env", "IMPACT/Hammer-v1", "--method", "vanilla_dp,augmented_dp,impact,impact_warm",
         "--masses", "0.2,5,10", "--episodes", "5"]
SETTINGS = {
    "workers2": ["--workers", "2"],
    "workers2_again": ["--workers", "2"],
    "workers1": ["--workers", "1"],
    "envs_per_worker1": ["--workers", "2", "--envs-per-worker", "1"],
    "ray": ["--executor", "ray"],
}


def impact_eval(args: list[str]) -> subprocess.Popen:
    """Start ``python -m impact_eval ARGS`` (output discarded but for errors)."""
    return subprocess.Popen([sys.executable, "-m", "impact_eval", *args],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


def finish(proc: subprocess.Popen, what: str) -> None:
    """Wait for ``proc``; raise with its last error line if it failed."""
    _, err = proc.communicate()
    if proc.returncode != 0:
        raise RuntimeError(f"{what} exited {proc.returncode}: {(err or '').strip()[-300:]}")


def rows_written(csv: Path) -> int:
    """Complete rows in a growing episodes.csv (header excluded)."""
    try:
        return max(0, csv.read_bytes().count(b"\n") - 1)
    except FileNotFoundError:
        return 0


def killed_and_resumed(out: Path, sweep: list[str], kill_after: int) -> None:
    """SIGKILL a run once it has ``kill_after`` rows, then resume it regrouped."""
    proc = impact_eval([*sweep, "--out", str(out), "--workers", "2"])
    while rows_written(out / "episodes.csv") < kill_after and proc.poll() is None:
        time.sleep(0.2)
    if proc.poll() is not None:
        raise RuntimeError("the run finished before it could be killed; lower --kill-after")
    proc.kill()  # SIGKILL: no cleanup; the orphaned workers exit by themselves
    proc.wait()
    finish(impact_eval([*sweep, "--out", str(out), "--resume", "--workers", "1",
                        "--envs-per-worker", "2"]), "resume")


def main(argv: list[str] | None = None) -> int:
    """CLI entry point."""
    parser = OneLineParser(prog="determinism_matrix", description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--kill-after", type=int, default=12)
    parser.add_argument("--skip", default="", help="comma list of settings to leave out")
    args = parser.parse_args(argv)
    if args.out.exists():
        parser.fail(f"--out {args.out} exists; give a new directory")
    skip = set(filter(None, args.skip.split(",")))
    digests: dict[str, str] = {}
    walls: dict[str, float] = {}
    for name, extra in [*SETTINGS.items(), ("killed_resumed", None)]:
        if name in skip:
            continue
        if name == "ray" and not _has_ray():
            print("ray: skipped (Ray is not installed: pip install -e '.[ray]')")
            continue
        out = args.out / name
        t0 = time.perf_counter()
        if extra is None:
            killed_and_resumed(out, SWEEP, args.kill_after)
        else:
            finish(impact_eval([*SWEEP, "--out", str(out), *extra]), name)
        walls[name] = time.perf_counter() - t0
        digests[name] = hashlib.sha256((out / "episodes.csv").read_bytes()).hexdigest()
        print(f"{name}: sha256 {digests[name]} ({walls[name]:.0f} s)", flush=True)
    identical = len(set(digests.values())) == 1
    (args.out / "determinism_matrix.json").write_text(json.dumps(
        {"sweep": SWEEP, "settings": SETTINGS, "sha256": digests, "wall_s": walls,
         "identical": identical}, indent=2) + "\n")
    print(f"all {len(digests)} episodes.csv {'identical' if identical else 'NOT identical'}")
    return 0 if identical else 1


def _has_ray() -> bool:
    try:
        import ray  # noqa: F401
    except ImportError:
        return False
    return True


if __name__ == "__main__":
    raise SystemExit(main())
