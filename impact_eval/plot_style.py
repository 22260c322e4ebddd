"""The look shared by every figure of a sweep: method order, labels, colours, markers, axis
labels and how a figure is saved (matplotlib ``Agg``, PNG + PDF)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

from impact_envs.tasks.registry import TASKS  # noqa: E402

METHOD_ORDER = ("scripted", "scripted_impact", "vanilla_dp", "augmented_dp", "impact")
METHOD_LABELS = {
    "scripted": "Scripted + impedance",
    "scripted_impact": "Scripted + IMPACT ctrl",
    "vanilla_dp": "Vanilla DP",
    "augmented_dp": "Augmented DP",
    "impact": "IMPACT (ours)",
    "impact_warm": "IMPACT, warm robot",
    "impact_paper": "IMPACT, paper preset",
    "impact_vanilla": "IMPACT, Vanilla ckpt",
    "scripted_impact_paper": "Scripted + IMPACT (paper)",
    "impact_authors": "IMPACT, authors' controller",
    "scripted_impact_authors": "Scripted + authors' IMPACT",
}
FORMATS = ("png", "pdf")
MARKERS = ("o", "s", "^", "D", "v", "P", "X")
LINESTYLES = ("-", "--", "-.", ":")
"""Markers and dashes cycle per method so that coinciding curves stay distinguishable."""


def ordered_methods(methods: list[str]) -> list[str]:
    """Known methods in the paper's order, then any others alphabetically."""
    known = [m for m in METHOD_ORDER if m in methods]
    return known + sorted(m for m in methods if m not in METHOD_ORDER)


def method_label(method: str) -> str:
    """Legend text of a method (``sb3:dir/ppo.zip`` -> ``SB3 ppo``)."""
    if method.startswith("sb3:"):
        return f"SB3 {Path(method[4:]).stem}"
    return METHOD_LABELS.get(method, method)


def param_label(summary: pd.DataFrame) -> str:
    """Axis label of a summary's parameter with the unit its task declares
    (``TaskParam.unit``), e.g. ``object mass [kg]``; no unit for a plugin env's parameter."""
    env_id, name = str(summary["env_id"].iloc[0]), str(summary["param_name"].iloc[0])
    task = TASKS.get(env_id.split(":")[-1])
    unit = next((p.unit for p in task.params if p.name == name), "") if task else ""
    text = name.replace("_", " ")
    return f"{text} [{unit}]" if unit else text


def method_colors(methods: list[str]) -> dict[str, tuple]:
    """Stable colour per method (tab10 by position in the paper's order)."""
    cmap = plt.get_cmap("tab10")
    return {m: cmap(i % 10) for i, m in enumerate(ordered_methods(methods))}


def save_figure(fig: plt.Figure, out_dir: Path, stem: str) -> list[Path]:
    """Save ``fig`` as PNG and PDF; returns the paths."""
    paths = []
    for fmt in FORMATS:
        path = out_dir / f"{stem}.{fmt}"
        fig.savefig(path, dpi=150, bbox_inches="tight")
        paths.append(path)
    plt.close(fig)
    return paths
