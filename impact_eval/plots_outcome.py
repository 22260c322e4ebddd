"""Energy and safety figures with successful and failed episodes apart, mean ± std (the band
clipped to each cell's smallest and largest value: these quantities cannot be negative).

A failed episode is often cheap (nothing was lifted) and a successful one expensive, so a mean
over both mixes two populations; each cell is drawn once per outcome, with its spread.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from impact_eval.metrics import SUSTAINED_PEAK_COLUMN
from impact_eval.plot_style import (
    LINESTYLES,
    MARKERS,
    method_colors,
    method_label,
    ordered_methods,
    param_label,
    save_figure,
)
from impact_eval.safety import SUSTAINED_PEAK_WINDOW_S

OUTCOMES = ((True, "successful episodes"), (False, "failed episodes"))


def outcome_stats(episodes: pd.DataFrame, column: str) -> pd.DataFrame:
    """Mean, std, count, min and max of ``column`` per (method, param_value, success)."""
    grouped = episodes.groupby(["method", "param_value", "success"])[column]
    return grouped.agg(["mean", "std", "count", "min", "max"]).reset_index()


def std_band(rows: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """The band drawn around each cell's mean: mean ± std, clipped to the smallest and largest
    value of the cell. Forces, times and energies cannot be negative, and a mean ± std band
    of a skewed cell (most episodes 0 N, a few 500 N) would otherwise reach below zero; the
    clipped band never leaves the values the episodes took."""
    mean, std = rows["mean"].to_numpy(float), rows["std"].fillna(0.0).to_numpy(float)
    low = np.maximum(mean - std, rows["min"].to_numpy(float))
    high = np.minimum(mean + std, rows["max"].to_numpy(float))
    return low, high


def _outcome_lines(ax: plt.Axes, stats: pd.DataFrame, success: bool, methods: list[str]) -> None:
    """One line per method with a ± std band, for the episodes of one outcome."""
    colors = method_colors(methods)
    for i, method in enumerate(methods):
        rows = stats[(stats["method"] == method) & (stats["success"] == success)]
        rows = rows.sort_values("param_value")
        if rows.empty:
            continue
        x, y = rows["param_value"].to_numpy(float), rows["mean"].to_numpy(float)
        ax.plot(x, y, marker=MARKERS[i % len(MARKERS)], ls=LINESTYLES[i % len(LINESTYLES)],
                ms=3.5, lw=1.5, color=colors[method], label=method_label(method))
        ax.fill_between(x, *std_band(rows), color=colors[method], alpha=0.15, lw=0)
    ax.grid(alpha=0.3)


def _grid(episodes: pd.DataFrame, summary: pd.DataFrame, columns: list[tuple[str, str]],
          title: str) -> plt.Figure:
    """Rows: outcome; columns: the quantities; one legend for the figure."""
    methods = ordered_methods(episodes["method"].unique().tolist())
    fig, axes = plt.subplots(len(OUTCOMES), len(columns), squeeze=False,
                             figsize=(5.2 * len(columns), 6.4), sharex=True)
    for c, (column, label) in enumerate(columns):
        stats = outcome_stats(episodes, column)
        for r, (success, name) in enumerate(OUTCOMES):
            ax = axes[r][c]
            _outcome_lines(ax, stats, success, methods)
            ax.set_title(f"{label}: {name}", fontsize=9)
            ax.set_ylabel(label, fontsize=8)
            if r == len(OUTCOMES) - 1:
                ax.set_xlabel(param_label(summary))
    handles = {h.get_label(): h for ax in axes.flat for h in ax.get_lines()}
    fig.legend(list(handles.values()), list(handles), loc="lower center",
               ncol=min(len(handles), 4), fontsize=8, frameon=False)
    fig.suptitle(f"{summary['env_id'].iloc[0]}: {title} (mean ± std per cell, the band "
                 "clipped to the cell's range)", fontsize=10)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    return fig


def plot_energy(episodes: pd.DataFrame, summary: pd.DataFrame, out_dir: Path,
                stem: str) -> list[Path]:
    """Energy per episode vs parameter, successful and failed episodes apart."""
    fig = _grid(episodes, summary,
                [("energy_j", r"energy $\int|\tau\cdot\dot q|\,dt$ [J]")], "energy")
    return save_figure(fig, out_dir, stem)


def plot_safety(episodes: pd.DataFrame, summary: pd.DataFrame, out_dir: Path,
                stem: str) -> list[Path]:
    """Sustained peak contact force (``safety.sustained_peak``: the highest force held for
    50 ms), the sustained-contact measures (95th percentile of the contact force, time above
    libfranka's example threshold of 20 N) and peak joint torque, successful and failed
    episodes apart.
    The raw peak contact force (one instant, a few-ms impact spike) stays in episodes.csv and
    summary.csv only. Tables written before a column existed get its panel left out; one
    without the sustained peak (before 2026-11-27) gets the raw peak in its place, so
    labelled."""
    columns = [safety_peak_column(episodes),
               ("contact_p95_n", "contact force, 95th percentile [N]"),
               ("contact_over_20n_s", "time above 20 N [s]"),
               ("peak_torque_nm", "peak joint torque [Nm]")]
    fig = _grid(episodes, summary, [c for c in columns if c[0] in episodes.columns], "safety")
    return save_figure(fig, out_dir, stem)


def safety_peak_column(episodes: pd.DataFrame) -> tuple[str, str]:
    """``(column, axis label)`` of the peak panel of the safety figure: the sustained peak,
    or the raw peak, labelled as such, for a table that predates it."""
    if SUSTAINED_PEAK_COLUMN in episodes.columns:
        held_ms = SUSTAINED_PEAK_WINDOW_S * 1000.0
        return SUSTAINED_PEAK_COLUMN, f"peak contact force held {held_ms:g} ms [N]"
    return "peak_contact_force_n", "raw peak contact force (no sustained peak in table) [N]"


__all__ = ["outcome_stats", "plot_energy", "plot_safety", "safety_peak_column",
           "std_band"]
