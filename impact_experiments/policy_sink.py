"""``python -m impact_experiments.policy_sink``: how high a policy carried the hammer in
a bin sweep's episodes (issue 55: the mechanism in the faithful Vanilla DP's failures).

Replays, one env at a time, the episodes of ``--method`` in the bins whose lower edges
``--bins`` names, from ``--table``'s ``episodes.csv`` (each row's seed and drawn mass), and
writes per episode what ``demo_sink.CarryProbe`` measures (clearance over the basket wall
while crossing it carried, the TCP's lowest height there, a touch of the basket), plus the
hammer's highest lift while the hand is closed (``max_lift_m``), the replay's success and the
table's (``table_success``). Each episode is seeded as the sweep's rollout seeds it (global
RNGs, then the policy's per-episode noise, then the env), so a replay is the table's episode:
the two successes agree unless an episode is chaotic. (Until 2026-12-02 the policy's noise was
left unseeded, and the replays were other draws of the same episodes.) ``--out`` is a new
CSV, written episode by episode.

    python -m impact_experiments.policy_sink --table results/hammer_basket_authors \\
        --method vanilla_dp_authors --bins 1.0 --out results/hammer_basket_diag/sink_va.csv
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pandas as pd

from impact_control.cli import OneLineParser
from impact_experiments.demo_sink import ENV_ID, CarryProbe

COLUMNS = ("method", "bin_lo", "seed", "episode", "mass_kg", "table_success", "success", "hit",
           "clearance_m", "crossing_tcp_m", "first_success_step", "max_lift_m")


def replay(method: str, rows: pd.DataFrame):
    """Yield one output row per table row (replayed in order)."""
    import impact_envs  # noqa: F401 - registers the envs
    from impact_control.policy import SeededPolicy, stack_obs
    from impact_eval.envs import method_env
    from impact_eval.methods import resolve_method
    from impact_eval.rollout import seed_global_rngs

    spec = resolve_method(method)
    env = method_env(ENV_ID, spec)
    policy = spec.build(ENV_ID, env)
    for r in rows.itertuples():
        seed = int(r.seed)  # seeded as the sweep's rollout seeds an episode, in its order
        seed_global_rngs(seed)
        policy.reset(1)
        if isinstance(policy, SeededPolicy):
            policy.seed_envs([seed])
        obs, info = env.reset(seed=seed, options={"object_mass": float(r.drawn_mass_kg)})
        probe, done = CarryProbe(env), False
        while not done:
            action = np.asarray(policy.act(stack_obs([obs]))[0])
            obs, _, terminated, truncated, info = env.step(action)
            probe.update(obs, action, info)
            done = terminated or truncated
        lift = probe.max_lift if math.isfinite(probe.max_lift) else math.nan
        yield {"method": method, "bin_lo": r.param_value, "seed": r.seed, "episode": r.episode,
               "mass_kg": r.drawn_mass_kg, "table_success": r.success, **probe.row(),
               "max_lift_m": lift}
    env.close()


def main(argv: list[str] | None = None) -> None:
    """Entry point; bad input exits 2 with one line, before anything is written."""
    p = OneLineParser(description=__doc__.splitlines()[0])
    p.add_argument("--table", type=Path, required=True, help="a HammerBasket bin sweep")
    p.add_argument("--method", required=True)
    p.add_argument("--bins", required=True, help="comma list of bins' lower edges [kg]")
    p.add_argument("--failed-only", action="store_true", help="only the table's failures")
    p.add_argument("--out", type=Path, required=True)
    args = p.parse_args(argv)
    csv_path = args.table / "episodes.csv"
    if not csv_path.is_file():
        p.fail(f"--table {str(args.table)!r} has no episodes.csv; valid: a sweep's folder")
    if args.out.exists():
        p.fail(f"--out {str(args.out)!r} exists; valid: a new file (nothing is overwritten)")
    table = pd.read_csv(csv_path, keep_default_na=False)
    if set(table["env_id"]) != {ENV_ID} or "drawn_mass_kg" not in table:
        p.fail(f"--table {str(args.table)!r} is not a {ENV_ID} bin sweep; valid: impact-eval "
               "--mass-bins on it")
    try:
        bins = [float(x) for x in args.bins.split(",") if x]
    except ValueError:
        p.fail(f"invalid --bins {args.bins!r}; valid: a comma list of bins' lower edges [kg]")
    rows = table[(table["method"] == args.method) & table["param_value"].isin(bins)]
    if args.failed_only:
        rows = rows[rows["success"] == 0]
    if rows.empty:
        p.fail(f"no rows of method {args.method!r} in bins {args.bins!r}; valid methods: "
               f"{', '.join(sorted(set(table['method'])))}; bins: "
               f"{', '.join(map(str, sorted(set(table['param_value']))))}")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("x", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        for row in replay(args.method, rows):
            writer.writerow(row)
            f.flush()


if __name__ == "__main__":
    main()
