"""How many demos an ``impact-collect`` store's expert lost, per mass band (issue 55: their
demonstrator's failed demos are dropped, counted and reported).

``python -m impact_experiments.demo_yield --data STORE [--bands 5]`` recomputes every
attempt's drawn mass from the store's seed and range (``collect_run.attempt_param``) and
compares with the attempts kept (``meta/episode_attempt``). Attempts after the last kept one
are left out: the last batch may hold successes beyond the demos asked for. Prints one line
per band; writes nothing.
"""

from __future__ import annotations

import argparse

import numpy as np

from impact_control.errors import ImpactError, InvalidArgumentError
from impact_learn.collect_config import CollectConfig
from impact_learn.collect_run import attempt_param
from impact_learn.store_check import open_store


def yield_by_band(data: str, bands: int) -> list[str]:
    """The report's lines: band, attempts, kept, failed."""
    root = open_store(data)
    spec = dict(root.attrs).get("param_spec", {})
    if spec.get("mode") != "uniform" or "meta/episode_attempt" not in root:
        raise InvalidArgumentError(f"{data}: not a store drawn from a range; valid: a store "
                                   "written by impact-collect --mass-range")
    low, high = map(float, spec["values"])
    cfg = CollectConfig(env_id=root.attrs["env_id"], out=data, seed=int(root.attrs["seed"]),
                        param_range=(low, high))
    kept = set(int(a) for a in root["meta/episode_attempt"][:])
    attempts = np.arange(max(kept) + 1)
    masses = np.array([attempt_param(cfg, int(a)) for a in attempts])
    ok = np.array([a in kept for a in attempts])
    edges = np.linspace(low, high, bands + 1)
    lines = [f"{data}: {ok.sum()} kept of {len(attempts)} attempts ({(~ok).sum()} failed), "
             f"expert {dict(root.attrs).get('expert')}"]
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        inside = (masses >= lo) & (masses < hi if hi < high else masses <= hi)
        n, k = int(inside.sum()), int(ok[inside].sum())
        lines.append(f"  {lo:5.2f}-{hi:5.2f} kg: {k} kept of {n} attempts ({n - k} failed)")
    return lines


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--data", required=True, help="an impact-collect store")
    p.add_argument("--bands", type=int, default=4, help="equal mass bands over the range")
    args = p.parse_args(argv)
    if args.bands < 1:
        p.error("--bands must be >= 1")
    try:
        print("\n".join(yield_by_band(args.data, args.bands)))
    except ImpactError as exc:
        p.error(" ".join(str(exc).split()))


if __name__ == "__main__":
    main()
