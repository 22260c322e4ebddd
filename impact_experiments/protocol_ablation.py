"""Adaptation-protocol phase times with issue 26's fields of `default` reverted (a diagnosis).

``python -m impact_experiments.protocol_ablation [VARIANT ...]`` runs the 6 s-hold
protocol of ``impact-protocol --repeats 10 --hold-s 6`` (Dumbbell 2.5 → 2.5 → 5 kg, seeds
0, 100, …, 900) with IMPACT in each variant and prints the median time from lift-off to
< 1 cm and the median settled peak error per phase. Variants: ``default`` (as shipped),
``no_guard``, ``numpy_learner``, ``clip_1000`` (the per-tick 1000 Nm/s clip) and
``old_default`` (all three reverted: the `default` before 2026-11-26). docs/results.md §3.
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import pandas as pd

from impact_control.config import ControllerConfig, LimitsConfig
from impact_control.presets import preset_config
from impact_experiments import adaptation


def variants() -> dict[str, ControllerConfig]:
    """The configurations by name."""
    d = preset_config("default")
    out = {"default": d,
           "no_guard": replace(d, guard=replace(d.guard, enabled=False)),
           "numpy_learner": replace(d, internal_model=replace(d.internal_model,
                                                              learner="numpy")),
           "clip_1000": replace(d, limits=LimitsConfig(torque_rate_max_nm_per_s=1000.0,
                                                       rate_limiter="per_tick_clip"))}
    out["old_default"] = replace(out["no_guard"],
                                 internal_model=out["numpy_learner"].internal_model,
                                 limits=out["clip_1000"].limits)
    return out


def main(argv: list[str] | None = None) -> None:
    choices = variants()
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", default=list(choices), choices=list(choices))
    parser.add_argument("--repeats", type=int, default=10)
    args = parser.parse_args(argv)
    for name in args.names:
        adaptation.PROTOCOL_CONTROLLERS = {name: ("impact", choices[name])}
        metrics = pd.concat([adaptation.phase_metrics(adaptation.run_sequence(
            "IMPACT/Dumbbell-v1", name, (2.5, 2.5, 5.0), seed=100 * k, hold_s=6.0))
            for k in range(args.repeats)])
        table = metrics.groupby("phase")[["adapt_liftoff_s", "peak_err_z_settled_m"]].median()
        print(name, table.round(3).to_dict())


if __name__ == "__main__":
    main()
