"""Grasped-load set-down (issue 37 item 4), the second scenario of the press experiment.

Run ``python -m impact_experiments.press --scenario setdown --out results/press``
(``setdown.csv``; docs/controller.md, "Grasped-load set-down"). The closed hand (140 N, the
Franka Hand's largest grasp force) holds a free 100 x 60 x 120 mm box of ``--loads-kg``
between its finger pads at HOME_Q (setdown_scene.xml). A weld holds the load for the first
``GRASP_S`` while the grasp force builds and is then switched off: the fingers carry it by
friction (pads mu 1.0: 280 N of grip against 59 N at 6 kg; the load's slip in the hand is
measured, ``max_slip_mm``). Sequence, every mode the same:

1. carry ``CARRY_S`` = 5 s in free space at the start pose (each controller settles and
   learns the weight; the table is ``CLEAR_M`` = 250 mm below the load, more than the 147 mm
   plain impedance sags at 6 kg plus its overshoot);
2. move the TCP target down in ``MOVE_S`` = 1 s (cosine profile) to the same absolute target
   for every controller: ``--setdown-depths`` [mm] below the TCP height at which the load's
   bottom touches the table (whatever the controller's own sag);
3. hold ``--hold-s`` seconds (6 s by default).

Measured (privileged, from the simulator): the total normal force of the table on the load
(raw: the load's weight m g is reported beside it, ``weight_n``) and the robot's own contact
with the table. ``press_n``: the largest 50 ms moving mean of the load's table force from 1 s
after arrival to the end of the hold; ``last_s_mean_n``: its mean over the last second;
``touchdown_n``: the largest 50 ms mean from the move's start to 1 s after arrival (the
touchdown, outside the acceptance measure); ``max_ff_n``: the largest fed-forward force [N]
(norm, world frame) from the move's start to the end; ``carry_ff_z_n``: the fed-forward
vertical force at the end of the carry (the weight the controller carries); ``final_ff_z_n``
/ ``final_ff_xy_n``: its vertical / horizontal part at the end (what the controller still
holds up, or pushes down with when negative); ``carry_sag_mm``: how far the TCP hangs below
its target at the end of the carry; ``holds``: contact-guard holds (``impact``).
Acceptance (issue 37): ``impact`` presses at most impedance's ``press_n`` + 3 N at each
(load, depth); the other modes are measured the same way and not held to it.
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Iterable, Sequence
from pathlib import Path

import mujoco
import numpy as np
import pandas as pd

from impact_control.controller import ImpactController
from impact_control.errors import InvalidArgumentError, check_choice
from impact_control.ik import HOME_Q
from impact_envs.envs.options import RobotOptions, apply_robot_overrides
from impact_envs.envs.robot_parts import build_robot
from impact_envs.loop import control_tick
from impact_envs.robot.sim import FrankaSim
from impact_experiments.physics import Rig
from impact_experiments.press_modes import TRACES, check_robot_record, mode_controller

SCENE, LOAD, TABLE, WELD = "setdown_scene.xml", "setdown_load", "setdown_table", "setdown_grasp"
LOAD_CENTRE_IN_HAND_M, LOAD_HALF_WIDTH_M, LOAD_BELOW_TCP_M = 0.1534, 0.03, 0.11
TABLE_HALF_THICKNESS_M, GRASP_FORCE_N = 0.02, 140.0
CARRY_S, MOVE_S, GRASP_S, CLEAR_M = 5.0, 1.0, 0.3, 0.25
WINDOW_S, PRESS_FROM_S, BOUND_N, TRACE_EVERY = 0.05, 1.0, 3.0, 10
KEY = ("mode", "load_kg", "depth_mm", "hold_s", "seed")
COLUMNS = (*KEY, "weight_n", "press_n", "last_s_mean_n", "touchdown_n", "carried_table_max_n",
           "hand_table_max_n", "max_ff_n", "carry_ff_z_n", "final_ff_z_n", "final_ff_xy_n",
           "carry_sag_mm", "max_slip_mm", "holds", "press_over_impedance_n")
"""``setdown.csv``'s columns; the last is filled when the run ends (impedance's row known)."""


def moving_mean(x: np.ndarray, n: int) -> np.ndarray:
    """Mean of each ``n`` consecutive samples of ``x`` (windows wholly inside; len - n + 1)."""
    c = np.concatenate([[0.0], np.cumsum(np.asarray(x, dtype=float))])
    return (c[n:] - c[:-n]) / n


def press_measure(force: np.ndarray, dt: float) -> tuple[float, float]:
    """(press, last-second mean) of a hold's force trace sampled every ``dt``: the largest
    ``WINDOW_S`` moving mean over windows from ``PRESS_FROM_S`` to the end, and the mean of
    the last second."""
    start, n = round(PRESS_FROM_S / dt), round(WINDOW_S / dt)
    return (float(moving_mean(force[start:], n).max()),
            float(np.mean(force[-round(1.0 / dt):])))


def setdown_robot(overrides: Sequence[str] = ()) -> RobotOptions:
    """The set-down's robot: the ideal one with sensor noise and a ``GRASP_FORCE_N`` grip,
    ``FIELD=VALUE`` ``overrides`` on top (``--robot-set``, e.g. ``realism=fr3``)."""
    return apply_robot_overrides(RobotOptions(grasp_force_n=GRASP_FORCE_N), overrides)


def setdown_rig(mode: str, load_kg: float, seed: int, robot: RobotOptions | None = None) -> Rig:
    """The set-down scene with the load's mass set, and the mode's controller (its preset as
    shipped: ``authors_sim`` compensates gravity in the controller like every preset here, the
    simulation has none built in, and rate-limits the command with gravity from 0 at reset);
    the robot is ``robot`` (default ``setdown_robot()``)."""
    ctrl_mode, cfg = mode_controller(mode)
    sim, arm, _ = build_robot(robot or setdown_robot(), SCENE, (LOAD,))
    body = sim.model.body(LOAD).id
    sim.model.body_inertia[body] *= load_kg / sim.model.body_mass[body]
    sim.model.body_mass[body] = load_kg
    mujoco.mj_setConst(sim.model, sim.data)  # the solver's inverse weights of the new mass
    return Rig(sim, arm, ImpactController(arm, cfg, mode=ctrl_mode), np.random.default_rng(seed))


def grasp_load(rig: Rig) -> tuple[np.ndarray, np.ndarray]:
    """Arm at rest at HOME_Q, the load between the pads (fingers on its faces, weld on), the
    table ``CLEAR_M`` below the load; returns the TCP target (position, quaternion)."""
    sim = rig.sim
    m, d = sim.model, sim.data
    start, quat = rig.start(HOME_Q)
    d.qpos[sim.finger_qpos] = LOAD_HALF_WIDTH_M
    mujoco.mj_forward(m, d)
    hand = m.body("hand").id
    adr = m.jnt_qposadr[m.joint("setdown_load_free").id]
    d.qpos[adr:adr + 3] = d.xpos[hand] + d.xmat[hand].reshape(3, 3)[:, 2] * LOAD_CENTRE_IN_HAND_M
    d.qpos[adr + 3:adr + 7] = d.xquat[hand]
    d.eq_active[m.equality(WELD).id] = 1
    top = start[2] - LOAD_BELOW_TCP_M - CLEAR_M
    d.mocap_pos[m.body(TABLE).mocapid[0]] = (start[0], start[1], top - TABLE_HALF_THICKNESS_M)
    mujoco.mj_forward(m, d)
    return start, quat


def load_in_hand(sim: FrankaSim) -> np.ndarray:
    """The load's centre in the hand frame [m] (privileged; slip check)."""
    d, hand = sim.data, sim.model.body("hand").id
    return d.xmat[hand].reshape(3, 3).T @ (d.xpos[sim.model.body(LOAD).id] - d.xpos[hand])


def target_z(start_z: float, depth_m: float, k: int, n_carry: int, n_move: int) -> float:
    """The TCP target height at tick ``k``: the carry height, a cosine move in ``n_move``
    ticks, then ``depth_m`` below the height at which the load's bottom touches the table."""
    goal = start_z - CLEAR_M - depth_m
    s = min(1.0, max(0.0, (k - n_carry) / n_move))
    return start_z + (goal - start_z) * (0.5 - 0.5 * math.cos(math.pi * s))


def simulate(rig: Rig, depth_m: float, hold_s: float, carry_s: float) -> dict[str, np.ndarray]:
    """Run carry, move and hold; per-tick traces (time, target and TCP height, load-table and
    robot-table force, fed-forward force, load slip)."""
    sim = rig.sim
    start, quat = grasp_load(rig)
    dt = sim.dt
    n_carry, n_move = round(carry_s / dt), round(MOVE_S / dt)
    n = n_carry + n_move + round(hold_s / dt)
    names = ("target_z", "tcp_z", "load_table_n", "hand_table_n", "ff_z_n", "ff_xy_n",
             "slip_mm")
    tr = {"t_s": (np.arange(n) + 1) * dt} | {name: np.zeros(n) for name in names}
    weld, ref, target = sim.model.equality(WELD).id, None, start.copy()
    ff = rig.controller.signals.wrench_ff_world
    for k in range(n):
        if k == round(GRASP_S / dt):
            sim.data.eq_active[weld] = 0
        target[2] = target_z(start[2], depth_m, k, n_carry, n_move)
        control_tick(sim, rig.controller, rig.rng, target, quat, 1.0)
        tr["target_z"][k], tr["tcp_z"][k] = target[2], sim.tcp_pose()[0][2]
        tr["hand_table_n"][k], tr["load_table_n"][k] = sim.contact_forces()
        tr["ff_z_n"][k], tr["ff_xy_n"][k] = ff[2], math.hypot(ff[0], ff[1])
        pos = load_in_hand(sim)
        ref = pos if ref is None or k < round(GRASP_S / dt) else ref
        tr["slip_mm"][k] = 1e3 * np.linalg.norm(pos - ref)
    return tr


def setdown(mode: str, load_kg: float, depth_m: float, hold_s: float, seed: int,
            carry_s: float = CARRY_S, robot: RobotOptions | None = None
            ) -> tuple[dict, pd.DataFrame]:
    """One set-down: its row (``COLUMNS``, without the comparison to impedance) and its trace
    (every ``TRACE_EVERY``-th tick, with the 50 ms moving mean of the load-table force)."""
    rig = setdown_rig(mode, load_kg, seed, robot)
    tr = simulate(rig, depth_m, hold_s, carry_s)
    dt = rig.sim.dt
    n_carry, n_arrive = round(carry_s / dt), round((carry_s + MOVE_S) / dt)
    press, last = press_measure(tr["load_table_n"][n_arrive:], dt)
    n = round(WINDOW_S / dt)
    mean = np.full_like(tr["load_table_n"], np.nan)
    mean[n - 1:] = moving_mean(tr["load_table_n"], n)
    tr["load_table_mean50_n"] = mean
    row = {"mode": mode, "load_kg": load_kg, "depth_mm": 1e3 * depth_m, "hold_s": hold_s,
           "seed": seed, "weight_n": load_kg * float(-rig.sim.model.opt.gravity[2]),
           "press_n": press, "last_s_mean_n": last,
           "touchdown_n": float(mean[n_carry:n_arrive + round(PRESS_FROM_S / dt)].max()),
           "carried_table_max_n": float(tr["load_table_n"][:n_carry].max()),
           "hand_table_max_n": float(tr["hand_table_n"].max()),
           "max_ff_n": float(np.hypot(tr["ff_z_n"], tr["ff_xy_n"])[n_carry:].max()),
           "carry_ff_z_n": float(tr["ff_z_n"][n_carry - 1]),
           "final_ff_z_n": float(tr["ff_z_n"][-1]), "final_ff_xy_n": float(tr["ff_xy_n"][-1]),
           "carry_sag_mm": 1e3 * float(tr["target_z"][n_carry - 1] - tr["tcp_z"][n_carry - 1]),
           "max_slip_mm": float(tr["slip_mm"].max()),
           "holds": rig.controller.guard.holds_started, "press_over_impedance_n": math.nan}
    return row, pd.DataFrame(tr).iloc[TRACE_EVERY - 1::TRACE_EVERY]


def row_key(row: dict) -> tuple[str, float, float, float, int]:
    """The resume key of a row (``KEY``), from a result or a row read back from the CSV."""
    return (str(row["mode"]), float(row["load_kg"]), float(row["depth_mm"]),
            float(row["hold_s"]), int(row["seed"]))


def read_rows(path: Path) -> list[dict]:
    """The complete rows of ``setdown.csv`` (none if it does not exist; a last line cut short
    by a crash is dropped)."""
    if not path.exists():
        return []
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):  # a crash mid-row: drop the cut line
        with path.open("r+b") as f:
            f.truncate(data.rfind(b"\n") + 1)
    with path.open(newline="") as f:
        reader = csv.DictReader(f)
        rows = list(reader)
    if reader.fieldnames is not None and tuple(reader.fieldnames) != COLUMNS:
        raise InvalidArgumentError(f"{path} has other columns than this version writes; valid: "
                                   "move it away (or pass another --out) and rerun")
    return [r for r in rows if None not in r and all(r.get(c) not in (None, "") for c in KEY)]


def append_row(path: Path, row: dict) -> None:
    """Append ``row`` (``COLUMNS``) to ``path``, header first if new; flushed and fsynced."""
    new = not path.exists() or path.stat().st_size == 0
    with path.open("a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS, lineterminator="\n")
        if new:
            writer.writeheader()
        writer.writerow({c: row[c] for c in COLUMNS})
        f.flush()
        os.fsync(f.fileno())


def impedance_press(rows: Iterable[dict], row: dict) -> float:
    """Impedance's ``press_n`` at ``row``'s load, depth, hold and seed (NaN if not run)."""
    want = row_key({**row, "mode": "impedance"})
    return next((float(r["press_n"]) for r in rows if row_key(r) == want), math.nan)


def finish_table(rows: list[dict], modes: Sequence[str]) -> pd.DataFrame:
    """The rows sorted by load, depth and mode, with ``press_over_impedance_n`` filled."""
    if not rows:
        return pd.DataFrame(columns=list(COLUMNS))
    df = pd.DataFrame([{c: r[c] for c in COLUMNS} for r in rows])
    df["press_over_impedance_n"] = [  # of the written values: a rewrite gives the same file
        round(float(r["press_n"]), 3) - round(impedance_press(rows, r), 3) for r in rows]
    order = {m: i for i, m in enumerate(modes)}
    df["_m"] = df["mode"].map(lambda m: order.get(m, len(order)))
    for c in COLUMNS[1:]:  # rows read back hold text
        df[c] = pd.to_numeric(df[c]).astype(int if c in ("seed", "holds") else float)
    return df.sort_values(["hold_s", "seed", "load_kg", "depth_mm", "_m"]).drop(columns="_m")


def write_table(path: Path, df: pd.DataFrame) -> None:
    """Rewrite ``setdown.csv`` atomically with the finished table."""
    tmp = path.with_name(path.name + ".tmp")
    df.to_csv(tmp, index=False, float_format="%.3f")
    os.replace(tmp, path)


def fails_bound(rows: list[dict], row: dict) -> bool:
    """Whether ``row`` is an ``impact`` set-down pressing more than impedance's + 3 N (or
    impedance's press is not known)."""
    return row["mode"] == "impact" and not row["press_n"] <= impedance_press(rows, row) + BOUND_N


def wants_trace(traces: str, rows: list[dict], row: dict) -> bool:
    """Whether ``row``'s trace is written under the ``--traces`` choice ``traces``."""
    return (traces == "all" or (traces == "impact" and row["mode"] == "impact")
            or (traces == "failing" and fails_bound(rows, row)))


def run_setdown(out: Path | None, modes: Sequence[str], loads_kg: Sequence[float],
                depths_mm: Sequence[float], hold_s: float, seed: int,
                traces: str = "failing", robot_set: Sequence[str] = ()) -> pd.DataFrame:
    """Every (load, depth, mode) set-down; with ``out``, each row is appended to
    ``out/setdown.csv`` as it finishes and rows already there are skipped (resume); the file
    is rewritten sorted, with the comparison to impedance, at the end. ``traces`` (one of
    ``TRACES``) says whose traces go to ``out/setdown_traces``: "failing" (``impact`` rows
    above impedance + 3 N), "impact" (every ``impact`` row), "all" or "none". ``robot_set``
    (``FIELD=VALUE``, ``setdown_robot``) is the robot, kept in ``out/robot.json``: a resume
    with another robot is refused (no file: the ideal robot)."""
    check_choice("traces", traces, TRACES)
    robot = setdown_robot(robot_set)
    path = None if out is None else out / "setdown.csv"
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        check_robot_record(out, robot_set)
    rows = [] if path is None else read_rows(path)
    done = {row_key(r) for r in rows}
    for load in loads_kg:
        for depth in depths_mm:
            for mode in modes:
                if row_key({"mode": mode, "load_kg": load, "depth_mm": depth,
                            "hold_s": hold_s, "seed": seed}) in done:
                    continue
                row, trace = setdown(mode, load, depth * 1e-3, hold_s, seed, robot=robot)
                rows.append(row)
                print(f"{mode:16s} {load:4.1f} kg {depth:4.0f} mm: press {row['press_n']:7.1f} N"
                      f" last 1 s {row['last_s_mean_n']:7.1f} N (m g {row['weight_n']:.1f} N)"
                      f" max ff {row['max_ff_n']:6.1f} N", flush=True)
                if path is not None:
                    append_row(path, row)
                    if wants_trace(traces, rows, row):
                        save_trace(out, row, trace)
    df = finish_table(rows, modes)
    if path is not None and rows:
        write_table(path, df)
    return df


def save_trace(out: Path, row: dict, trace: pd.DataFrame) -> Path:
    """``out/setdown_traces/MODE_LOADkg_DEPTHmm.csv``: the run's trace (10 ms samples)."""
    folder = out / "setdown_traces"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{row['mode']}_{row['load_kg']:g}kg_{row['depth_mm']:g}mm.csv"
    trace.to_csv(path, index=False, float_format="%.5g")
    print(f"trace: {path}", flush=True)
    return path
