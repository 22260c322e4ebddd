"""``summary.csv`` and plots, computed from ``episodes.csv`` alone (``impact-eval report DIR``)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from impact_control.errors import InvalidArgumentError
from impact_eval.metrics import (
    ADDED_COLUMNS,
    EPISODE_COLUMNS,
    SUSTAINED_COLUMNS,
    SUSTAINED_PEAK_COLUMN,
    wilson_interval,
)

EPISODES_CSV = "episodes.csv"
SUMMARY_CSV = "summary.csv"
PLOTS_DIR = "plots"

SUMMARY_COLUMNS: tuple[str, ...] = (
    "method",
    "env_id",
    "param_name",
    "param_value",
    "n",
    "successes",
    "success_rate",
    "ci_low",
    "ci_high",
    "success_once_rate",
    "energy_mean_j",
    "energy_std_j",
    "peak_torque_mean_nm",
    "peak_contact_sustained_mean_n",
    "peak_contact_force_mean_n",
    "contact_p95_mean_n",
    "contact_over_20n_mean_s",
    "pose_error_mean_m",
    "time_to_success_mean_s",
    "n_unstable",
    "n_exception",
)
"""Columns of ``summary.csv``: one row per (method, parameter value). The safety measure is
``peak_contact_sustained_mean_n`` (``safety.sustained_peak``); the raw peak follows it."""

OPTIONAL_COLUMNS: tuple[str, ...] = ADDED_COLUMNS["2026-11-27"]
"""``episodes.csv`` columns a table written before 2026-11-27 lacks and the report still
reads without: the summary's ``peak_contact_sustained_mean_n`` is then NaN and the safety
figure draws the raw peak instead (``plots_outcome.plot_safety``)."""


INTEGER_COLUMNS = ("seed", "episode", "success", "success_once", "length")
FLOAT_COLUMNS = ("param_value", "time_to_success_s", "energy_j", "peak_torque_nm",
                 "peak_contact_force_n", SUSTAINED_PEAK_COLUMN, "contact_p95_n",
                 "contact_over_10n_s", "contact_over_20n_s", "mean_pose_error_m",
                 "drawn_mass_kg")


def load_episodes(out_dir: Path) -> pd.DataFrame:
    """Read and check ``out_dir/episodes.csv``; ``InvalidArgumentError`` (one line naming the
    file, the row and the column) if it is missing, empty, torn or holds a malformed value.
    A table without the ``OPTIONAL_COLUMNS`` (an older impact-eval's) is read as it is: those
    columns stay absent."""
    path = Path(out_dir) / EPISODES_CSV
    if not path.is_file():
        raise InvalidArgumentError(f"{path} not found; run impact-eval with --out {out_dir} first")
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        raise InvalidArgumentError(
            f"{path} ends in a row cut mid-line (a run killed while writing); rerun the sweep "
            "with --resume and the same arguments, which drops it, or delete that last line")
    try:
        df = pd.read_csv(path, keep_default_na=False, na_values=["nan", "NaN"])
    except (ValueError, pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise InvalidArgumentError(f"cannot read {path}: {' '.join(str(exc).split())}") from None
    missing = [c for c in EPISODE_COLUMNS if c not in df.columns and c not in OPTIONAL_COLUMNS]
    if missing:
        older = " (written by an impact-eval before 2026-11-26: rerun the sweep)" if set(
            missing) <= set(SUSTAINED_COLUMNS) else ""
        raise InvalidArgumentError(f"{path} lacks columns {', '.join(missing)}{older}")
    if df.empty:
        raise InvalidArgumentError(f"{path} has no episodes")
    for column in (*INTEGER_COLUMNS, *FLOAT_COLUMNS):
        if column in df.columns:
            _check_numeric(path, df, column)
    for column in ("failure_reason", "robot_profile"):
        if column in df.columns:
            df[column] = df[column].fillna("").astype(str)
    return df


def _check_numeric(path: Path, df: pd.DataFrame, column: str) -> None:
    """One-line error naming the first row whose ``column`` is not a valid number (ints and
    0/1 flags where the column holds them); the parsed values are left as pandas read them."""
    values = pd.to_numeric(df[column], errors="coerce")
    bad = values.isna() & df[column].notna()
    if column in INTEGER_COLUMNS:
        bad |= values.isna() | (values != values.round())
    if column in ("success", "success_once"):
        bad |= ~values.isin([0, 1])
    if bad.any():
        row = int(bad.to_numpy().argmax())
        valid = "0 or 1" if column.startswith("success") else (
            "an integer" if column in INTEGER_COLUMNS else "a number")
        raise InvalidArgumentError(
            f"{path} row {row + 2}: invalid {column} {df[column].iloc[row]!r}; valid: {valid} "
            "(fix or delete the row)")


def _summarize_group(g: pd.DataFrame) -> dict[str, object]:
    """Summary statistics of the episodes of one (method, value) cell."""
    n, k = len(g), int(g["success"].sum())
    low, high = wilson_interval(k, n)
    reasons = g["failure_reason"]
    return {
        "n": n,
        "successes": k,
        "success_rate": k / n,
        "ci_low": low,
        "ci_high": high,
        "success_once_rate": float(g["success_once"].mean()),
        "energy_mean_j": g["energy_j"].mean(),
        "energy_std_j": g["energy_j"].std(),
        "peak_torque_mean_nm": g["peak_torque_nm"].mean(),
        "peak_contact_sustained_mean_n": _mean(g, SUSTAINED_PEAK_COLUMN),
        "peak_contact_force_mean_n": g["peak_contact_force_n"].mean(),
        "contact_p95_mean_n": g["contact_p95_n"].mean(),
        "contact_over_20n_mean_s": g["contact_over_20n_s"].mean(),
        "pose_error_mean_m": g["mean_pose_error_m"].mean(),
        "time_to_success_mean_s": g["time_to_success_s"].mean(),
        "n_unstable": int(reasons.str.startswith("unstable").sum()),
        "n_exception": int(reasons.str.startswith("exception").sum()),
    }


def _mean(g: pd.DataFrame, column: str) -> float:
    """Mean of ``column`` over the cell; NaN when the table has no such column (older)."""
    return float(g[column].mean()) if column in g.columns else float("nan")


def summarize(episodes: pd.DataFrame) -> pd.DataFrame:
    """One row per (method, parameter value), sorted; see ``SUMMARY_COLUMNS``."""
    rows = []
    keys = ["method", "env_id", "param_name", "param_value"]
    for key, group in episodes.groupby(keys, sort=True):
        rows.append({**dict(zip(keys, key, strict=True)), **_summarize_group(group)})
    return pd.DataFrame(rows, columns=list(SUMMARY_COLUMNS))


def success_table_markdown(summary: pd.DataFrame) -> str:
    """Markdown table: one row per parameter value, one column per method, cells
    ``successes/n (rate %, Wilson 95 % CI)``; what docs/results.md quotes."""
    name = str(summary["param_name"].iloc[0]) if len(summary) else "value"
    methods = list(dict.fromkeys(summary["method"]))
    lines = [f"| {name} | " + " | ".join(methods) + " |",
             "|---" * (len(methods) + 1) + "|"]
    for value, group in summary.groupby("param_value", sort=True):
        cells = []
        by_method = group.set_index("method")
        for method in methods:
            if method not in by_method.index:
                cells.append("—")
                continue
            r = by_method.loc[method]
            cells.append(f"{int(r['successes'])}/{int(r['n'])} ({r['success_rate']:.0%}, "
                         f"{r['ci_low']:.0%}–{r['ci_high']:.0%})")
        lines.append(f"| {value:g} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def write_report(out_dir: Path) -> tuple[Path, list[Path]]:
    """Write ``summary.csv``, ``summary.md`` (success table) and every plot from
    ``episodes.csv``.

    Returns:
        ``(summary_path, plot_paths)``.
    """
    from impact_eval.plots import plot_all

    out_dir = Path(out_dir)
    episodes = load_episodes(out_dir)
    plots = out_dir / PLOTS_DIR
    if plots.exists() and not plots.is_dir():
        raise InvalidArgumentError(f"{plots} is not a directory; move it away to draw the plots")
    summary = summarize(episodes)
    summary_path = out_dir / SUMMARY_CSV
    tmp = summary_path.with_name(SUMMARY_CSV + ".tmp")
    summary.to_csv(tmp, index=False)
    tmp.replace(summary_path)
    (out_dir / "summary.md").write_text(success_table_markdown(summary))
    return summary_path, plot_all(summary, plots, episodes)
