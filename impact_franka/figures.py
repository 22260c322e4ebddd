"""``impact-protocol``'s figure from a hardware run's ``ticks.csv`` (``impact-robot hold``)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from impact_eval.experiments.adaptation import plot


def protocol_frame(ticks: pd.DataFrame, controller: str) -> pd.DataFrame:
    """The columns ``impact_eval.experiments.adaptation.plot`` draws, from ``ticks.csv``'s
    (one episode, phase "hold")."""
    return pd.DataFrame({
        "controller": controller, "episode": 0, "phase": "hold", "t_s": ticks["t_s"],
        "ext_fz": ticks["wrench_ext_z_n"], "slow_fz": ticks["wrench_slow_z_n"],
        "pred_fz": ticks["wrench_pred_z_n"], "imp_fz": ticks["wrench_imp_z_n"],
        "ff_fz": ticks["wrench_ff_z_n"], "gate_open": ticks["gate_open"].astype(bool),
        "err_z_m": ticks["pos_error_z_m"], "pose_error_m": ticks["pos_error_m"]})


def plot_ticks(ticks: pd.DataFrame, controller: str, out_dir: Path) -> list[Path]:
    """``out_dir/protocol.png`` and ``.pdf``: vertical force signals, gate, TCP error."""
    return plot(protocol_frame(ticks, controller), Path(out_dir) / "protocol.png")
