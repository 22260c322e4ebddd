"""Figures of a sweep, drawn from ``summary.csv`` (matplotlib ``Agg``, PNG + PDF).

1. ``success_surface``: 3-D bars, x = parameter (object mass), y = method, z = success rate
   (the layout of the paper's simulation-benchmark figure).
2. ``success_vs_<param>``: success rate with Wilson 95 % bands, one line per method.
3. ``energy_vs_<param>``: joint mechanical energy per episode, mean ± std.
4. ``safety_vs_<param>``: sustained peak contact force (held 50 ms), sustained contact (p95,
   time above 20 N), peak joint torque, means (``plots_outcome.plot_safety``).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from impact_eval.plot_style import (  # noqa: E402, F401 - style names, re-exported
    FORMATS,
    LINESTYLES,
    MARKERS,
    METHOD_LABELS,
    METHOD_ORDER,
    method_colors,
    method_label,
    ordered_methods,
    param_label,
    save_figure,
)
from impact_eval.plots_outcome import plot_energy, plot_safety  # noqa: E402


def _bar_width(values: np.ndarray) -> float:
    """Bar width along the parameter axis: 70 % of the smallest gap, at most 8 % of the span."""
    unique = np.unique(values)
    if unique.size < 2:
        return 0.5 * max(1.0, abs(float(unique[0]))) if unique.size else 0.5
    return min(0.7 * float(np.diff(unique).min()), 0.08 * float(unique[-1] - unique[0]))


def plot_surface(summary: pd.DataFrame, out_dir: Path) -> list[Path]:
    """3-D bar chart: parameter × method × success rate (one ``bar3d`` call, correct depth)."""
    methods = ordered_methods(summary["method"].unique().tolist())
    colors = method_colors(methods)
    dx, dy = _bar_width(summary["param_value"].to_numpy(float)), 0.45
    rows = summary.assign(j=summary["method"].map(methods.index)).sort_values(["j", "param_value"])
    x = rows["param_value"].to_numpy(float) - dx / 2
    y = rows["j"].to_numpy(float) - dy / 2
    fig = plt.figure(figsize=(10, 6))
    ax = fig.add_subplot(projection="3d")
    ax.bar3d(
        x,
        y,
        np.zeros(len(x)),
        dx,
        dy,
        rows["success_rate"].to_numpy(float),
        color=[colors[m] for m in rows["method"]],
        shade=True,
        edgecolor="0.25",
        linewidth=0.15,
    )
    ax.set_box_aspect((2.2, 1.1, 0.8))
    ax.set_xlim(float(x.min()) - dx / 2, float(x.max()) + 1.5 * dx)
    ax.set_xlabel(param_label(summary), labelpad=12)
    ax.set_yticks(range(len(methods)))
    ax.set_yticklabels(
        [method_label(m) for m in methods],
        fontsize=8,
        verticalalignment="baseline",
        horizontalalignment="left",
    )
    ax.set_ylim(-0.6, len(methods) - 0.4)
    ax.set_zlabel("success rate", labelpad=4)
    ax.set_zlim(0, 1)
    ax.set_zticks([0, 0.25, 0.5, 0.75, 1.0])
    ax.view_init(elev=28, azim=-58)
    ax.set_title(
        f"{summary['env_id'].iloc[0]}: success rate by method and "
        f"{param_label(summary)}",
        pad=0,
    )
    return save_figure(fig, out_dir, "success_surface")


def _lines(
    ax: plt.Axes,
    summary: pd.DataFrame,
    mean: str,
    low: str | None,
    high: str | None,
) -> None:
    """One line per method with an optional band between columns ``low`` and ``high``."""
    methods = ordered_methods(summary["method"].unique().tolist())
    colors = method_colors(methods)
    for i, method in enumerate(methods):
        rows = summary[summary["method"] == method].sort_values("param_value")
        x, y = rows["param_value"].to_numpy(float), rows[mean].to_numpy(float)
        ax.plot(
            x,
            y,
            marker=MARKERS[i % len(MARKERS)],
            ls=LINESTYLES[i % len(LINESTYLES)],
            ms=3.5,
            lw=1.5,
            color=colors[method],
            label=method_label(method),
        )
        if low and high:
            ax.fill_between(x, rows[low], rows[high], color=colors[method], alpha=0.15, lw=0)
    ax.grid(alpha=0.3)
    ax.ticklabel_format(axis="y", useOffset=False)
    ax.set_xlabel(param_label(summary))


def plot_success(summary: pd.DataFrame, out_dir: Path, stem: str) -> list[Path]:
    """Success rate vs parameter with Wilson 95 % bands."""
    fig, ax = plt.subplots(figsize=(7, 4.2))
    _lines(ax, summary, "success_rate", "ci_low", "ci_high")
    ax.set_ylim(-0.03, 1.03)
    ax.set_ylabel("success rate (Wilson 95 % CI)")
    lo, hi = int(summary["n"].min()), int(summary["n"].max())
    n = str(lo) if lo == hi else f"{lo}–{hi}"
    ax.set_title(f"{summary['env_id'].iloc[0]}: success rate (n = {n} episodes per point)")
    ax.legend(fontsize=8, loc="best")
    return save_figure(fig, out_dir, stem)


def plot_heatmap(summary: pd.DataFrame, out_dir: Path) -> list[Path]:
    """Success as an annotated heatmap: one row per method (the paper's order), one column per
    parameter value, each cell ``successes/n`` over its rate (colour: rate, red 0 to green 1)."""
    methods = ordered_methods(summary["method"].unique().tolist())
    values = np.sort(summary["param_value"].unique())
    rate = np.full((len(methods), len(values)), np.nan)
    text = np.full(rate.shape, "", dtype=object)
    for row in summary.itertuples():
        i, j = methods.index(row.method), int(np.searchsorted(values, row.param_value))
        rate[i, j] = row.success_rate
        text[i, j] = f"{row.successes}/{row.n}\n{row.success_rate:.0%}"
    fig, ax = plt.subplots(figsize=(max(6.0, 0.62 * len(values) + 2.5),
                                    max(2.5, 0.55 * len(methods) + 1.4)))
    image = ax.imshow(rate, cmap="RdYlGn", vmin=0.0, vmax=1.0, aspect="auto")
    for (i, j), label in np.ndenumerate(text):
        if label:
            dark = 0.25 < rate[i, j] < 0.75
            ax.text(j, i, label, ha="center", va="center", fontsize=7,
                    color="black" if dark else "white" if rate[i, j] <= 0.25 else "black")
    ax.set_xticks(range(len(values)), [f"{v:g}" for v in values], fontsize=8)
    ax.set_yticks(range(len(methods)), [method_label(m) for m in methods], fontsize=8)
    ax.set_xlabel(param_label(summary))
    fig.colorbar(image, ax=ax, fraction=0.03, pad=0.02, label="success rate")
    ax.set_title(f"{summary['env_id'].iloc[0]}: successes / episodes per cell", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, out_dir, "success_heatmap")


def plot_all(summary: pd.DataFrame, out_dir: Path, episodes: pd.DataFrame) -> list[Path]:
    """Draw every figure into ``out_dir`` (created if needed); returns the files written.
    Energy and safety split the episodes of each cell by outcome (``plots_outcome.py``)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    param = str(summary["param_name"].iloc[0])
    return [
        *plot_heatmap(summary, out_dir),
        *plot_surface(summary, out_dir),
        *plot_success(summary, out_dir, f"success_vs_{param}"),
        *plot_energy(episodes, summary, out_dir, f"energy_vs_{param}"),
        *plot_safety(episodes, summary, out_dir, f"safety_vs_{param}"),
    ]
