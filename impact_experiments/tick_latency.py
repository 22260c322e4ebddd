"""Worst-case cost of one 1 kHz control tick, learning included (the real-time budget).

Run ``python -m impact_experiments.tick_latency --seconds 60 --out DIR`` with no
environment variable set. The arm holds a pose in the payload scene while the welded payload
switches every ``--switch-s`` seconds through 0, 2.5 and 5 kg, so the surprise gate keeps
re-opening and the internal model keeps learning. Each tick is timed around
``ImpactController.compute`` alone (dynamics update, every stage, the learner's share),
the call a robot runner makes once per 1 ms cycle; the simulator step is not timed.
The thread's own CPU time is recorded beside the wall time: a tick whose wall time is far
above its CPU time was preempted by the OS (a 2-core machine shared with other processes; a
robot PC runs the loop on an isolated core with a real-time kernel). Prints and writes
(``DIR/latency.json``) the percentiles, the maximum and the count over the
budget, for all ticks and for learning ticks (gate open), per learner of the shipped
``default`` (contact guard on, libfranka's limits), or of ``--preset NAME``: ``numba`` (its
learner since 2026-11-26: inside the tick, spread over ticks) and ``numpy`` (Python + BLAS
after the tick, the learner before that date). Budget (issue 26): p99.9 <= 0.3 ms and max
<= 0.8 ms per tick on one core
of the 2-core development machine. The gripper is commanded open on the first tick and
closed from the second, so a preset's lift watch (``lift_watch``) arms and runs its counting
path on every tick, as in a heavy lift it cannot see rise.
"""

from __future__ import annotations

import argparse
import gc
import json
import platform
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from impact_control.controller import ImpactController
from impact_control.ik import HOME_Q
from impact_control.presets import PRESETS, preset_config
from impact_experiments.physics import Rig

PAYLOADS_KG = (0.0, 2.5, 5.0)
BUDGET_P999_S, BUDGET_MAX_S = 0.3e-3, 0.8e-3


def measure(learner: str, seconds: float, switch_s: float, seed: int,
            preset: str = "default") -> dict[str, np.ndarray]:
    """Per-tick compute time [s] and learning flag over ``seconds`` of simulated hold."""
    rig = Rig.build("payload_scene.xml", "impact", "residual", seed)
    base = preset_config(preset)  # default: guard on, libfranka's limits, numba
    cfg = replace(base, internal_model=replace(base.internal_model, learner=learner))
    ctrl = ImpactController(rig.arm, cfg, mode="impact")
    rig = Rig(rig.sim, rig.arm, ctrl, rig.rng)
    sim, model = rig.sim, rig.sim.model
    body = model.body("payload").id
    inertia = model.body_inertia[body] / model.body_mass[body]
    pos, quat = rig.start(HOME_Q)
    n, every = round(seconds / sim.dt), round(switch_s / sim.dt)
    cost, cpu = np.zeros(n), np.zeros(n)
    learning, collected = np.zeros(n, bool), np.zeros(n, bool)
    gc_runs = [0]

    def on_gc(phase: str, info: dict) -> None:
        gc_runs[0] += phase == "start"

    gc.callbacks.append(on_gc)
    clock, cpu_clock = time.perf_counter_ns, time.thread_time_ns
    for k in range(n):
        if k % every == 0:
            mass = max(PAYLOADS_KG[(k // every) % len(PAYLOADS_KG)], 1e-6)
            model.body_mass[body], model.body_inertia[body] = mass, inertia * mass
        q, dq, tau_meas = sim.read_sensors(rig.rng)
        width = sim.gripper_width()
        runs, c0, t0 = gc_runs[0], cpu_clock(), clock()
        tau = ctrl.compute(q, dq, tau_meas, pos, quat, gripper_width_m=width,
                           gripper_cmd=1.0 if k else -1.0)
        cost[k] = (clock() - t0) * 1e-9
        cpu[k] = (cpu_clock() - c0) * 1e-9
        collected[k] = gc_runs[0] != runs
        learning[k] = ctrl.signals.gate_open
        sim.apply(tau, -1.0)
        sim.step()
    gc.callbacks.remove(on_gc)
    return {"cost_s": cost, "cpu_s": cpu, "learning": learning, "gc": collected,
            "updates": np.array([ctrl.internal_model.n_updates])}


def summarize(cost: np.ndarray) -> dict[str, float]:
    """Percentiles, max [us] and counts over the budget of per-tick costs [s]."""
    if cost.size == 0:
        return {"ticks": 0}
    pct = np.percentile(cost, [50, 99, 99.9]) * 1e6
    return {"ticks": int(cost.size), "p50_us": float(pct[0]), "p99_us": float(pct[1]),
            "p999_us": float(pct[2]), "max_us": float(cost.max() * 1e6),
            "over_0.3ms": int((cost > BUDGET_P999_S).sum()),
            "over_0.8ms": int((cost > BUDGET_MAX_S).sum())}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--switch-s", type=float, default=5.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--learners", nargs="+", default=["numpy", "numba"],
                        choices=["numpy", "numba"])
    parser.add_argument("--preset", default="default",
                        choices=[p for p in PRESETS if not p.startswith("authors")])
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    if not (args.seconds > 0 and args.switch_s > 0):
        parser.error(f"--seconds {args.seconds} / --switch-s {args.switch_s}: valid: > 0")
    given = sys.argv[1:] if argv is None else argv
    report: dict[str, object] = {"command": "python -m impact_experiments.tick_latency "
                                 + " ".join(given), "machine": platform.processor()
                                 or platform.machine(), "seconds": args.seconds,
                                 "preset": args.preset}
    print("| learner | ticks | SGD steps | p50 [us] | p99 [us] | p99.9 [us] | max [us] | > 0.3 ms "
          "| > 0.8 ms | learning ticks p99.9 [us] | learning ticks max [us] | budget met |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for learner in args.learners:
        measure(learner, 1.0, args.switch_s, args.seed, args.preset)  # compile and warm first
        r = measure(learner, args.seconds, args.switch_s, args.seed, args.preset)
        every, learn = summarize(r["cost_s"]), summarize(r["cost_s"][r["learning"]])
        met = every["p999_us"] <= 300.0 and every["max_us"] <= 800.0
        slow = r["cost_s"] > BUDGET_MAX_S
        report[learner] = {"all": every, "learning": learn, "sgd_steps": int(r["updates"][0]),
                           "budget_met": met, "ticks_with_gc": int(r["gc"].sum()),
                           "over_0.8ms_with_gc": int((slow & r["gc"]).sum()),
                           "over_0.8ms_cpu_under_0.3ms": int(
                               (slow & (r["cpu_s"] < BUDGET_P999_S)).sum()),
                           "thread_cpu": summarize(r["cpu_s"]),
                           "slowest_ticks_us": sorted((r["cost_s"] * 1e6).round(1))[-5:]}
        print(f"| {learner} | {every['ticks']} | {int(r['updates'][0])} | {every['p50_us']:.0f} | "
              f"{every['p99_us']:.0f} | {every['p999_us']:.0f} | {every['max_us']:.0f} | "
              f"{every['over_0.3ms']} | {every['over_0.8ms']} | {learn.get('p999_us', 0):.0f} | "
              f"{learn.get('max_us', 0):.0f} | {'yes' if met else 'no'} |")
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "latency.json").write_text(json.dumps(report, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
