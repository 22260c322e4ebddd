"""The numbers of docs/franka.md on when the force arrives: the 12 s undeclared-3 kg hold
(joints without friction) with the force switched on by a wall-clock timer ``DELAY`` s after
the command starts (the old mechanism), for each delay given.

    IMPACT_FRANKY_SIM_PYTHON=PATH/bin/python python tests/franka/onset_sensitivity.py 3 4 5 9

Prints per delay: the onset on the robot's clock, the largest TCP error from 1.5 s after the
onset on, the error at the end, and the learned weight [N] (m g = 29.43 N).
"""

from __future__ import annotations

import contextlib
import io
import sys
import tempfile
import threading
from pathlib import Path

import pandas as pd
from franka_servers import SIM_BUDGET, franky_scene

from impact_franka.cli import main as impact_robot


def main(delays: list[float]) -> None:
    for delay in delays:
        out = Path(tempfile.mkdtemp())
        flag = out / "on"
        with franky_scene("--load-kg", "3", "--no-joint-friction", "--flag", str(flag)) as host:
            timer = threading.Timer(delay, flag.touch)
            timer.start()
            with contextlib.redirect_stdout(io.StringIO()):
                status = impact_robot(["hold", *SIM_BUDGET, "--host", host, "--seconds", "12",
                                       "--controller", "impact", "--max-payload-kg", "3",
                                       "--out", str(out / "run")])
            timer.cancel()
        assert status == 0, f"impact-robot hold exited {status}"
        k = pd.read_csv(out / "run" / "ticks.csv")
        k = k[k["t_s"] <= 12.0].reset_index(drop=True)
        on = k.index[k["wrench_ext_z_n"].abs() > 10.0][0]
        t_on = float(k["t_s"][on])
        later = k[k["t_s"] >= t_on + 1.5]
        learned = k["wrench_pred_z_n"].iloc[-1] - k["wrench_pred_z_n"][max(on - 200, 0)]
        print(f"delay {delay:g} s: onset {t_on:.2f} s, max after 1.5 s "
              f"{1e3 * later['pos_error_m'].max():.2f} mm, end "
              f"{1e3 * k['pos_error_m'].iloc[-1]:.2f} mm, learned {learned:.2f} N", flush=True)


if __name__ == "__main__":
    main([float(v) for v in sys.argv[1:]] or [3.0, 4.0, 5.0, 9.0])
