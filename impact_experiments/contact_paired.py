"""``python -m impact_experiments.contact_paired``: what the authors' finger-hammer
contact changes on HammerBasket, on paired episodes (issue 55 item 6).

Each episode runs twice on the same seed and mass: once on ``IMPACT/HammerBasket-v1`` as it is
(our contact) and once with ``impact_envs.scenes_contact.use_their_finger_contact`` applied to
its compiled model (their mixed solref / solimp, no noslip). Masses are drawn uniformly in
``--mass-bin`` from each episode's seed. Rows (``--out``: a new CSV, appended per episode pair,
never overwritten) hold the success at the end, the first success step (-1 if none) and
whether the hammer dropped back to the table after a lift (``dropped``).

    python -m impact_experiments.contact_paired --method scripted --mass-bin 8-10 \\
        --episodes 50 --seed 0 --out results/hammer_basket_diag/contact_paired.csv
"""

from __future__ import annotations

import csv
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from impact_control.cli import OneLineParser
from impact_control.errors import ImpactError, InvalidArgumentError
from impact_eval.envs import check_masses

ENV_ID = "IMPACT/HammerBasket-v1"
COLUMNS = ("contact", "method", "mass_kg", "seed", "episode", "success", "first_success_step",
           "dropped")
LIFTED_M = 0.05
"""The hammer's origin this far above the table counts as lifted [m]."""


def run_pair(args: tuple[str, float, int, int]) -> list[dict[str, object]]:
    """Both contacts' rows of one episode (method, mass, seed, episode index)."""
    import impact_envs  # noqa: F401 - registers the envs
    from impact_control.policy import stack_obs
    from impact_envs.scenes_contact import use_their_finger_contact
    from impact_envs.tasks.hammer_basket import TABLE_TOP_M
    from impact_eval.envs import method_env
    from impact_eval.methods import resolve_method

    method, mass, seed, e = args
    rows = []
    for contact in ("ours", "theirs"):
        spec = resolve_method(method)
        env = method_env(ENV_ID, spec)
        if contact == "theirs":
            use_their_finger_contact(env.unwrapped.sim.model)
        policy = spec.build(ENV_ID, env)
        obs, info = env.reset(seed=seed, options={"object_mass": mass})
        policy.reset(1)
        first, lifted, dropped, done, step = -1, False, False, False, 0
        while not done:
            obs, _, terminated, truncated, info = env.step(policy.act(stack_obs([obs]))[0])
            height = float(obs["object_pos"][2]) - TABLE_TOP_M
            lifted = lifted or height > LIFTED_M
            dropped = dropped or (lifted and first < 0 and height < 0.02)
            if first < 0 and info.get("is_success", False):
                first = step
            done, step = terminated or truncated, step + 1
        rows.append({"contact": contact, "method": method, "mass_kg": mass, "seed": seed,
                     "episode": e, "success": int(bool(info.get("is_success", False))),
                     "first_success_step": first, "dropped": int(dropped)})
        env.close()
    return rows


def _bin(text: str) -> tuple[float, float]:
    """The one bin ``text`` names (``impact_envs.tasks.bins.parse_bins``'s syntax), in the task's
    mass range."""
    from impact_envs.tasks.bins import parse_bins

    bins = parse_bins(text)
    if len(bins) != 1:
        raise InvalidArgumentError(f"invalid --mass-bin {text!r}; valid: one LO-HI bin in kg")
    check_masses(ENV_ID, [bins[0].lo, bins[0].hi])
    return bins[0].lo, bins[0].hi


def main(argv: list[str] | None = None) -> None:
    """Entry point; bad input exits 2 with one line, before anything is written."""
    p = OneLineParser(description=__doc__.splitlines()[0])
    p.add_argument("--method", default="scripted")
    p.add_argument("--mass-bin", default="8-10")
    p.add_argument("--episodes", type=int, default=50)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--out", type=Path, required=True)
    args = p.parse_args(argv)
    if args.episodes < 1 or args.workers < 1:
        p.fail("--episodes and --workers must be >= 1")
    if args.out.exists():
        p.fail(f"--out {str(args.out)!r} exists; valid: a new file (nothing is overwritten)")
    try:
        from impact_eval.methods import resolve_method

        if resolve_method(args.method).carry:
            raise InvalidArgumentError(f"--method {args.method!r} carries state across "
                                       "episodes; valid: a method without +carry")
        low, high = _bin(args.mass_bin)
    except ImpactError as exc:
        p.fail(" ".join(str(exc).split()))
    pairs = [(args.method, float(np.random.default_rng([args.seed, e]).uniform(low, high)),
              args.seed + e, e) for e in range(args.episodes)]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("x", newline="") as f, ProcessPoolExecutor(args.workers) as pool:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        totals = {"ours": 0, "theirs": 0}
        for rows in pool.map(run_pair, pairs):
            writer.writerows(rows)
            f.flush()
            for r in rows:
                totals[r["contact"]] += r["success"]
        print(f"{args.method} {args.mass_bin} kg, {args.episodes} paired episodes: success "
              f"ours {totals['ours']}, theirs {totals['theirs']}")


if __name__ == "__main__":
    main()
