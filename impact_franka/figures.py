"""The adaptation protocol's figure, drawn from a simulated run (``impact-protocol``) or from a
hardware run's ``ticks.csv`` (``impact-robot hold``). It lives here, where the robot runner may
use it without the benchmark; ``impact_experiments.adaptation`` imports it."""

from __future__ import annotations

from pathlib import Path

import pandas as pd


def protocol_frame(ticks: pd.DataFrame, controller: str) -> pd.DataFrame:
    """The columns ``plot_protocol`` draws, from ``ticks.csv``'s
    (one episode, phase "hold")."""
    return pd.DataFrame({
        "controller": controller, "episode": 0, "phase": "hold", "t_s": ticks["t_s"],
        "ext_fz": ticks["wrench_ext_z_n"], "slow_fz": ticks["wrench_slow_z_n"],
        "pred_fz": ticks["wrench_pred_z_n"], "imp_fz": ticks["wrench_imp_z_n"],
        "ff_fz": ticks["wrench_ff_z_n"], "gate_open": ticks["gate_open"].astype(bool),
        "err_z_m": ticks["pos_error_z_m"], "pose_error_m": ticks["pos_error_m"]})


def plot_ticks(ticks: pd.DataFrame, controller: str, out_dir: Path) -> list[Path]:
    """``out_dir/protocol.png`` and ``.pdf``: vertical force signals, gate, TCP error."""
    return plot_protocol(protocol_frame(ticks, controller), Path(out_dir) / "protocol.png")


def plot_protocol(df: pd.DataFrame, path: Path) -> list[Path]:
    """The adaptation protocol's figure (``impact-protocol``'s and ``impact-robot hold``'s):
    stacked panels per controller: vertical force signals, gate, vertical pose error."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    controllers = list(dict.fromkeys(df["controller"]))
    fig, axes = plt.subplots(3, len(controllers), figsize=(6.5 * len(controllers), 7.5),
                             sharex="col", squeeze=False)
    for col, controller in enumerate(controllers):
        d = df[df["controller"] == controller]
        t = d["t_s"]
        ax = axes[0, col]
        ax.plot(t, d["ext_fz"], lw=0.6, alpha=0.5, label="raw estimate ŵ_z")
        ax.plot(t, d["slow_fz"], lw=1.5, label="slow wrench w_slow,z")
        ax.plot(t, d["pred_fz"], lw=1.5, ls="--", label="internal model w_pred,z")
        ax.plot(t, d["imp_fz"] + d["ff_fz"], lw=1.0, label="applied (impedance + ff) z")
        ax.set_ylabel("vertical force [N]")
        ax.set_title(f"controller = {controller}")
        ax.legend(fontsize=7, loc="lower left", ncol=2)  # the phase labels sit at the top
        axes[1, col].step(t, d["gate_open"].astype(int), where="post", color="tab:red")
        axes[1, col].set_ylabel("surprise gate open")
        axes[1, col].set_yticks([0, 1])
        ax3 = axes[2, col]
        ax3.plot(t, 100 * d["err_z_m"], lw=1.0, label="vertical error e_z")
        ax3.plot(t, 100 * d["pose_error_m"], lw=0.6, alpha=0.6, label="|position error|")
        ax3.axhspan(-1, 1, color="tab:green", alpha=0.12, label="±1 cm")
        ax3.set_ylabel("TCP error [cm]")
        ax3.set_xlabel("time [s] (episodes back to back)")
        ax3.legend(fontsize=7, loc="upper left")
        for _, ep in d.groupby("episode"):
            start, end = ep["t_s"].iloc[0], ep["t_s"].iloc[-1]
            for a in axes[:, col]:
                a.axvline(start, color="k", lw=0.5, alpha=0.4)
            axes[0, col].text((start + end) / 2, 0.97, f"Phase {ep['phase'].iloc[0]}",
                              transform=axes[0, col].get_xaxis_transform(), ha="center",
                              va="top", fontsize=9, weight="bold")
    fig.tight_layout()
    paths = [path.with_suffix(".png"), path.with_suffix(".pdf")]
    for p in paths:
        fig.savefig(p, dpi=130)
    plt.close(fig)
    return paths
