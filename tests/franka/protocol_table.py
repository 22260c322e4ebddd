"""The numbers of docs/franka.md "Payload and push in franky-sim": ``hold`` with a force that
arrives during the hold (franky_scene_server.py), for each controller, with and without the
simulated joints' Coulomb friction.

    IMPACT_FRANKY_SIM_PYTHON=PATH/bin/python python tests/franka/protocol_table.py [--out DIR]

Prints one row per run: the TCP error 0.5, 1.5 and 6 s after the force arrived, at the end,
and the learned force (the prediction's change along the force's axis, against it).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import tempfile
from pathlib import Path

import pandas as pd
from franka_servers import SIM_BUDGET, flag_at_loop_start, franky_scene_with_force

from impact_franka.cli import main as impact_robot

SCENES = {"3 kg load": (["--load-kg", "3"], "z", 3.0 * 9.81),
          "20 N push": (["--push-n", "20,0,0"], "x", -20.0)}
"""Scene options, the force's axis, and the force the controller should add [N]."""
SECONDS = 12.0


def _run(out: Path, options: list[str], controller: str) -> pd.DataFrame:
    flag = out / "on"
    with (franky_scene_with_force(*options, flag=flag) as host, flag_at_loop_start(flag),
          contextlib.redirect_stdout(io.StringIO())):
        status = impact_robot(["hold", *SIM_BUDGET, "--host", host, "--seconds", str(SECONDS),
                               "--controller", controller, "--max-payload-kg", "3",
                               "--out", str(out)])
    assert status == 0, f"impact-robot hold exited {status}"
    ticks = pd.read_csv(out / "ticks.csv")
    return ticks[ticks["t_s"] <= SECONDS].reset_index(drop=True)


def _row(ticks: pd.DataFrame, axis: str, force_n: float) -> dict[str, float]:
    on = ticks.index[ticks[f"wrench_ext_{axis}_n"].abs() > abs(force_n) / 3][0]
    t_on = ticks["t_s"][on]

    def error_mm(dt: float) -> float:
        i = int((ticks["t_s"] - t_on - dt).abs().argmin())
        return round(1e3 * float(ticks["pos_error_m"][i]), 1)

    pred = ticks[f"wrench_pred_{axis}_n"]
    learned = float(pred.iloc[-1] - pred[max(on - 200, 0)])
    end_mm = round(1e3 * float(ticks["pos_error_m"].iloc[-1]), 1)
    return {"error_0.5s_mm": error_mm(0.5), "error_1.5s_mm": error_mm(1.5),
            "error_6s_mm": error_mm(6.0), "error_end_mm": end_mm,
            "learned_n": round(learned, 2), "should_n": round(force_n, 2)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    root = args.out or Path(tempfile.mkdtemp(prefix="franky-protocol-"))
    rows = []
    for scene, (options, axis, force) in SCENES.items():
        for friction in (True, False):
            for controller in ("impact", "impedance"):
                out = root / f"{scene.replace(' ', '_')}_{controller}_{friction}"
                out.mkdir(parents=True, exist_ok=True)
                extra = [] if friction else ["--no-joint-friction"]
                ticks = _run(out, options + extra, controller)
                rows.append({"scene": scene, "joint_friction": friction,
                             "controller": controller, **_row(ticks, axis, force)})
                print(rows[-1], flush=True)
    print(pd.DataFrame(rows).to_string(index=False))


if __name__ == "__main__":
    main()
