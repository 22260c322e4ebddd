#!/usr/bin/env bash
# impact-bench of this checkout against an older commit, alternating, in one run (docs/controller.md):
#   bash impact_experiments/bench_against.sh REV [ROUNDS] [PYTHON]
# REV is checked out as a git worktree in a temporary folder and imported from there with
# PYTHONPATH (same interpreter, same packages); each round runs HEAD, then REV, with
# `python -m impact_eval.bench --steps 150 --repeat 5` (best of 5 per kind). Run it on an idle
# machine; compare the "env, ..." rows of the same round (their ratio), not across machines.
set -euo pipefail
rev=${1:?usage: bench_against.sh REV [ROUNDS] [PYTHON]}
rounds=${2:-6}
python=$(realpath -s "$(command -v "${3:-python}")")  # absolute: the rounds cd away
here=$(cd "$(dirname "$0")/../.." && pwd)
old=$(mktemp -d)/old
git -C "$here" worktree add -q --detach "$old" "$rev"
trap 'git -C "$here" worktree remove --force "$old"' EXIT
for round in $(seq 1 "$rounds"); do
  echo "=== round $round new $(git -C "$here" rev-parse --short HEAD)"
  (cd "$here" && OMP_NUM_THREADS=1 "$python" -m impact_eval.bench --steps 150 --repeat 5)
  echo "=== round $round old $rev"
  (cd "$old" && OMP_NUM_THREADS=1 PYTHONPATH="$old" "$python" -m impact_eval.bench --steps 150 --repeat 5)
done
