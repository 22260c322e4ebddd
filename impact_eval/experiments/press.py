"""Press experiment: a closed hand pushed into a rigid plate and held there (issue 26).

Run ``python -m impact_eval.experiments.press --out results/press``. The plate (press_scene.xml)
is tilted by each ``--angles`` [deg] about the world y axis (0: a table top, 90: a wall in front
of the hand) with its surface 30 mm from the TCP along its normal. The TCP target moves in 1 s
along the inward normal to ``--depths`` [mm] below the surface and stays there for
``--hold-s`` seconds; the hand cannot follow, so the impedance law presses with about
K x depth. Reported per mode: the steady contact force (mean of the last second), its growth
from 2 s after arrival to the end, and the largest predicted force [N]. Acceptance (issue 26):
with the contact guard (``impact``), steady force <= impedance's + 3 N, growth <= 0.5 N,
prediction bounded.

Modes: ``impedance``; ``impact`` (the ``default`` preset as shipped, contact guard on);
``impact_unguarded`` (``default`` with ``guard.enabled=False``); ``paper``. Sensor noise on,
seed ``--seed``.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import replace
from pathlib import Path

import mujoco
import numpy as np
import pandas as pd

from impact_envs.control.config import ControllerConfig
from impact_envs.control.controller import ImpactController
from impact_envs.control.presets import preset_config
from impact_envs.loop import control_tick
from impact_envs.robot.ik import HOME_Q
from impact_eval.experiments.physics import Rig

MODES = ("impedance", "impact", "impact_unguarded", "paper")
GAP_M, APPROACH_S, PLATE_HALF_THICKNESS_M = 0.03, 1.0, 0.02


def mode_controller(mode: str) -> tuple[str, ControllerConfig]:
    """(controller mode, config) of a press mode."""
    base = preset_config("paper" if mode == "paper" else "default")
    if mode == "impact_unguarded":
        base = replace(base, guard=replace(base.guard, enabled=False))
    return ("impedance" if mode == "impedance" else "impact"), base


def place_plate(model: mujoco.MjModel, data: mujoco.MjData, tcp: np.ndarray,
                angle_deg: float) -> np.ndarray:
    """Tilt the plate (a mocap body) by ``angle_deg`` about y with its surface ``GAP_M`` from
    the TCP along its normal; returns the outward unit normal."""
    phi = -math.radians(angle_deg)
    normal = np.array([math.sin(phi), 0.0, math.cos(phi)])
    mocap = model.body("press_plate").mocapid[0]
    data.mocap_pos[mocap] = tcp - (GAP_M + PLATE_HALF_THICKNESS_M) * normal
    data.mocap_quat[mocap] = (math.cos(phi / 2), 0.0, math.sin(phi / 2), 0.0)
    return normal


def press(mode: str, angle_deg: float, depth_m: float, hold_s: float, seed: int) -> dict:
    """One press; the steady force, its growth and the largest prediction."""
    ctrl_mode, cfg = mode_controller(mode)
    rig = Rig.build("press_scene.xml", "impedance", "residual", seed)
    rig = Rig(rig.sim, rig.arm, ImpactController(rig.arm, cfg, mode=ctrl_mode), rig.rng)
    sim = rig.sim
    start, quat = rig.start(HOME_Q)
    normal = place_plate(sim.model, sim.data, start, angle_deg)
    mujoco.mj_forward(sim.model, sim.data)
    goal = start - (GAP_M + depth_m) * normal
    n_app, n_hold = round(APPROACH_S / sim.dt), round(hold_s / sim.dt)
    force, pred = np.zeros(n_hold), np.zeros(n_hold)
    for k in range(n_app + n_hold):
        s = min(1.0, k / n_app)
        target = start + (goal - start) * (0.5 - 0.5 * math.cos(math.pi * s))
        control_tick(sim, rig.controller, rig.rng, target, quat, -1.0)
        if k >= n_app:
            force[k - n_app] = sim.contact_forces()[0]
            pred[k - n_app] = np.linalg.norm(rig.controller.signals.wrench_pred_world[:3])
    per_s = round(1.0 / sim.dt)
    steady = float(force[-per_s:].mean())
    at_2s = float(force[2 * per_s:3 * per_s].mean())
    return {"mode": mode, "angle_deg": angle_deg, "depth_mm": 1e3 * depth_m,
            "steady_force_n": steady, "growth_after_2s_n": steady - at_2s,
            "peak_force_n": float(force.max()), "max_pred_n": float(pred.max()),
            "final_pred_n": float(pred[-1]),
            "holds": rig.controller.guard.holds_started}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--angles", type=float, nargs="+", default=[0.0, 20.0, 40.0, 90.0])
    parser.add_argument("--depths", type=float, nargs="+", default=[10.0, 30.0, 50.0],
                        help="[mm] below the surface")
    parser.add_argument("--modes", nargs="+", default=list(MODES), choices=MODES)
    parser.add_argument("--hold-s", type=float, default=8.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    if not (args.hold_s >= 3.0 and all(d > 0 for d in args.depths)):
        parser.error(f"--hold-s {args.hold_s}, --depths {args.depths}: valid: hold >= 3 s "
                     "(growth is read from 2-3 s), depths > 0 mm")
    rows = []
    for angle in args.angles:
        for depth in args.depths:
            for mode in args.modes:
                rows.append(press(mode, angle, depth * 1e-3, args.hold_s, args.seed))
                r = rows[-1]
                print(f"{mode:13s} {angle:4.0f} deg {depth:4.0f} mm: steady "
                      f"{r['steady_force_n']:7.1f} N growth {r['growth_after_2s_n']:+6.2f} N "
                      f"max pred {r['max_pred_n']:7.1f} N holds {r['holds']}", flush=True)
    df = pd.DataFrame(rows)
    if "impedance" in args.modes:
        ref = df[df["mode"] == "impedance"].set_index(["angle_deg", "depth_mm"])["steady_force_n"]
        df["over_impedance_n"] = df["steady_force_n"] - [ref.get((a, d), np.nan) for a, d in
                                                         zip(df["angle_deg"], df["depth_mm"],
                                                             strict=True)]
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        df.to_csv(args.out / "press.csv", index=False, float_format="%.3f")
    print(df.to_string(index=False, float_format=lambda v: f"{v:.1f}"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
