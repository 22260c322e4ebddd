"""Press experiment: a closed hand pushed into a rigid plate and held there (issue 26), and a
grasped load set down on a table (issue 37 item 4, ``press_setdown.py``).

Run ``python -m impact_experiments.press --out results/press`` (both scenarios;
``--scenario plate`` or ``setdown`` for one). The plate (press_scene.xml)
is tilted by each ``--angles`` [deg] about the world y axis (0: a table top, 90: a wall in front
of the hand) with its surface 30 mm from the TCP along its normal. The TCP target moves in 1 s
along the inward normal to ``--depths`` [mm] below the surface and stays there for
``--hold-s`` seconds (8 by default); the hand cannot follow, so the impedance law presses with
about K x depth. Reported per mode: the steady contact force (mean of the last second), its
growth from 2 s after arrival to the end, and the largest predicted force [N] (``press.csv``).
Acceptance (issue 26): with the contact guard (``impact``), steady force <= impedance's + 3 N,
growth <= 0.5 N, prediction bounded. The set-down (``setdown.csv``, flags ``--loads-kg``,
``--setdown-depths``, ``--traces``; hold 6 s by default) is described in ``press_setdown.py``.

Modes: ``impedance``; ``impact`` (the ``default`` preset as shipped, contact guard on);
``impact_unguarded`` (``default`` with ``guard.enabled=False``); ``paper``; ``authors_sim``
(the authors' controller as their simulation runs it, the preset as shipped: gravity is
compensated by the controller, as in every mode here, and its torque-rate limit acts on the
command with gravity, starting from 0 at reset; the plate's ``max_pred_n`` is the internal
model's prediction, 0 here: its feedforward is the payload stage's). Sensor noise on, seed
``--seed``.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import mujoco
import numpy as np
import pandas as pd

from impact_control.cli import OneLineParser
from impact_control.controller import ImpactController
from impact_control.errors import InvalidArgumentError
from impact_control.ik import HOME_Q
from impact_envs.cli import add_robot_set
from impact_envs.envs.options import RobotOptions, apply_robot_overrides
from impact_envs.loop import control_tick
from impact_experiments.physics import Rig
from impact_experiments.press_modes import TRACES, check_robot_record, mode_controller
from impact_experiments.press_setdown import run_setdown

MODES = ("impedance", "impact", "impact_unguarded", "paper", "authors_sim", "lift_watch",
         "keep_carried")
DEFAULT_MODES = MODES[:5]
"""What ``--modes`` runs when not given (``lift_watch`` and ``keep_carried``, issue 54, only
when asked)."""
SCENARIOS = ("both", "plate", "setdown")
GAP_M, APPROACH_S, PLATE_HALF_THICKNESS_M = 0.03, 1.0, 0.02


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


def press(mode: str, angle_deg: float, depth_m: float, hold_s: float, seed: int,
          robot: RobotOptions | None = None) -> dict:
    """One press; the steady force, its growth and the largest prediction. ``robot``: the
    ideal robot with sensor noise by default."""
    ctrl_mode, cfg = mode_controller(mode)
    rig = Rig.build("press_scene.xml", "impedance", "residual", seed, robot=robot)
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


def _floats(text: str, flag: str, lo: float, hi: float, unit: str) -> list[float]:
    """The comma-separated numbers of ``flag``, each in (lo, hi]; else ValueError naming the
    valid values."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if not values or not all(lo < v <= hi for v in values):
        raise ValueError(f"invalid {flag} {text!r}; valid: comma-separated numbers in "
                         f"({lo:g}, {hi:g}] {unit}")
    return values


def _modes(values: list[str]) -> list[str]:
    """``--modes`` (space- or comma-separated) checked against ``MODES``."""
    modes = [m for v in values for m in v.split(",") if m]
    bad = [m for m in modes if m not in MODES]
    if bad or not modes:
        raise ValueError(f"invalid --modes {' '.join(values)!r}; valid: {', '.join(MODES)}")
    return modes


def _parser() -> OneLineParser:
    parser = OneLineParser(prog="press", description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", choices=SCENARIOS, default="both")
    parser.add_argument("--angles", type=float, nargs="+", default=[0.0, 20.0, 40.0, 90.0])
    parser.add_argument("--depths", type=float, nargs="+", default=[10.0, 30.0, 50.0],
                        help="plate: [mm] below the surface")
    parser.add_argument("--loads-kg", default="3,6", help="set-down: loads [kg], e.g. 3,6")
    parser.add_argument("--setdown-depths", default="15,30",
                        help="set-down: [mm] below the table contact, e.g. 15,30")
    parser.add_argument("--modes", nargs="+", default=list(DEFAULT_MODES),
                        help=", ".join(MODES))
    parser.add_argument("--hold-s", type=float, default=None,
                        help="hold [s] (default: plate 8, set-down 6)")
    parser.add_argument("--traces", choices=TRACES, default="failing",
                        help="set-down traces written to OUT/setdown_traces: failing (impact "
                             "above impedance + 3 N), impact, all, none")
    parser.add_argument("--seed", type=int, default=0)
    add_robot_set(parser, "OUT/robot.json")
    parser.add_argument("--out", type=Path, default=None)
    return parser


def _check(parser: OneLineParser, args: argparse.Namespace) -> None:
    """Parse the list flags in place; one line naming the valid values on a bad one."""
    try:
        args.modes = _modes(args.modes)
        args.loads_kg = _floats(args.loads_kg, "--loads-kg", 0.0, 10.0, "kg")
        args.setdown_depths = _floats(args.setdown_depths, "--setdown-depths", 0.0, 100.0, "mm")
    except ValueError as exc:
        parser.fail(exc)
    plate, setdown = args.scenario != "setdown", args.scenario != "plate"
    if plate and not (args.hold_s is None or args.hold_s >= 3.0):
        parser.fail(f"invalid --hold-s {args.hold_s}; valid: >= 3 s for the plate (growth is "
                    "read from 2-3 s)")
    if setdown and not (args.hold_s is None or 2.0 <= args.hold_s <= 60.0):
        parser.fail(f"invalid --hold-s {args.hold_s}; valid: 2 to 60 s for the set-down")
    if plate and not all(d > 0 for d in args.depths):
        parser.fail(f"invalid --depths {args.depths}; valid: depths > 0 mm")
    try:
        args.robot = apply_robot_overrides(None, args.robot_set)
        args.robot.resolved_realism()
    except InvalidArgumentError as exc:
        parser.fail(exc)


def run_plate(args: argparse.Namespace, hold_s: float) -> None:
    """The plate presses of ``args``; ``press.csv`` under ``args.out``."""
    rows = []
    for angle in args.angles:
        for depth in args.depths:
            for mode in args.modes:
                rows.append(press(mode, angle, depth * 1e-3, hold_s, args.seed, args.robot))
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
        check_robot_record(args.out, args.robot_set)
        df.to_csv(args.out / "press.csv", index=False, float_format="%.3f")
    print(df.to_string(index=False, float_format=lambda v: f"{v:.1f}"))


def main(argv: list[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    _check(parser, args)
    print(f"robot: {args.robot.resolved_realism()}")
    if args.scenario != "setdown":
        run_plate(args, 8.0 if args.hold_s is None else args.hold_s)
    if args.scenario != "plate":
        try:
            df = run_setdown(args.out, args.modes, args.loads_kg, args.setdown_depths,
                             6.0 if args.hold_s is None else args.hold_s, args.seed, args.traces,
                             args.robot_set)
        except InvalidArgumentError as exc:
            parser.fail(exc)
        print(df.to_string(index=False, float_format=lambda v: f"{v:.1f}"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
