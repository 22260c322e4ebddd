"""The energy and safety figures' ± std bands stay within the values the episodes took: a
force, a time or an energy cannot be negative, and a skewed cell (mostly 0 N, one 500 N) used
to draw its band far below zero."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402

from impact_eval import plots_outcome  # noqa: E402
from impact_eval.plots_outcome import outcome_stats, std_band  # noqa: E402

COLUMNS = ["peak_contact_sustained_n", "peak_contact_force_n", "contact_p95_n",
           "contact_over_20n_s", "peak_torque_nm", "energy_j"]


def _episodes() -> pd.DataFrame:
    """Two methods, two values, skewed cells: many zeros and one large value, both outcomes,
    one single-episode cell (std NaN)."""
    rows = []
    for method in ("impact", "vanilla_dp"):
        for value in (2.5, 5.0):
            for episode, big in enumerate([0.0, 0.0, 0.0, 0.0, 500.0]):
                rows.append({"method": method, "param_value": value, "episode": episode,
                             "success": int(episode == 0 and value == 5.0),
                             **{c: big * (1 + 0.1 * i) for i, c in enumerate(COLUMNS)}})
    return pd.DataFrame(rows).assign(env_id="IMPACT/Hammer-v1", param_name="object_mass")


@pytest.mark.parametrize("column", COLUMNS)
def test_band_is_within_each_cells_range(column: str) -> None:
    stats = outcome_stats(_episodes(), column)
    low, high = std_band(stats)
    assert (stats["mean"] - stats["std"].fillna(0) < 0).any()  # the unclipped band was < 0
    assert np.all(low >= stats["min"]) and np.all(low >= 0)
    assert np.all(high <= stats["max"]) and np.all(low <= stats["mean"] + 1e-12)
    assert np.all(high >= stats["mean"] - 1e-12)


def test_band_keeps_signed_quantities_and_single_episode_cells() -> None:
    """Not a clip at zero: a quantity that can be negative keeps its negative band, and a
    one-episode cell (std NaN) is a zero-width band at its value."""
    episodes = pd.DataFrame({"method": "m", "param_value": [1.0, 1.0, 1.0, 2.0],
                             "success": 1, "x": [-3.0, -1.0, 1.0, 7.0]})
    stats = outcome_stats(episodes, "x")
    low, high = std_band(stats)
    assert low[0] == pytest.approx(-3.0) and high[0] == pytest.approx(1.0)  # mean -1, std 2
    assert low[1] == high[1] == 7.0


@pytest.mark.parametrize("plot", ["plot_safety", "plot_energy"])
def test_the_drawn_bands_never_go_below_zero(plot: str, tmp_path, monkeypatch) -> None:
    """Read the polygons matplotlib actually filled in the saved figure."""
    figures: list[plt.Figure] = []

    def keep(fig, out_dir, stem):
        figures.append(fig)
        return []

    monkeypatch.setattr(plots_outcome, "save_figure", keep)
    episodes = _episodes()
    summary = episodes.groupby(["env_id", "param_name", "method"]).size().reset_index()
    getattr(plots_outcome, plot)(episodes, summary, tmp_path, "fig")
    bands = [poly for ax in figures[0].axes for poly in ax.collections]
    assert bands, "no band drawn"
    for poly in bands:
        for path in poly.get_paths():
            assert path.vertices[:, 1].min() >= 0.0
    assert "clipped to the cell's range" in figures[0]._suptitle.get_text()
    plt.close(figures[0])
