"""The paper authors' published success figure beside ours, on ``IMPACT/HammerBasket-v1``.

Run ``python -m impact_eval.experiments.authors_figure --table results/hammer_basket`` on a
bin sweep (``impact-eval --mass-bins``, their 8 bins). It prints, and writes to
``TABLE/authors_figure.md``, success per bin with its 95 % Wilson interval for every method,
their published rate beside each of their three rows, and issue 38's acceptance checks; it
draws ``TABLE/plots/authors_figure.{png,pdf}`` like theirs (success per bin and the mean),
their values as white diamonds on our bars of the same method.

Their values: ``resources/SR_3d.svg`` of ``Winston-Gu/IMPACT`` (gh-pages), read in
../shared/reference/authors_impact.md. Their IMPACT row is their controller, ours
``impact_authors``; their Augmented and Vanilla DP run under impedance, ours too.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pandas as pd

from impact_eval.metrics import wilson_interval

BINS = ((0.1, 0.3), (0.3, 0.5), (0.5, 1.0), (1.0, 2.0), (2.0, 4.0), (4.0, 6.0), (6.0, 8.0),
        (8.0, 10.0))
"""Their mass bins [kg], ``[lo, hi)``."""
PUBLISHED = {
    "impact_authors": (0.86, 0.88, 0.84, 0.76, 0.76, 0.62, 0.34, 0.26),
    "augmented_dp": (0.64, 0.68, 0.62, 0.58, 0.52, 0.38, 0.24, 0.00),
    "vanilla_dp": (0.70, 0.74, 0.56, 0.00, 0.00, 0.00, 0.00, 0.00),
}
"""Their published success per bin, under our names for their methods."""
ORDER = ("vanilla_dp", "augmented_dp", "impact_authors", "impact", "impact_paper")
LABELS = {"vanilla_dp": "Vanilla DP", "augmented_dp": "Augmented DP",
          "impact_authors": "IMPACT, their controller", "impact": "IMPACT, ours (default)",
          "impact_paper": "IMPACT, ours (paper)"}


def bin_rates(episodes: pd.DataFrame) -> pd.DataFrame:
    """Per method and bin (its lower edge): episodes, successes, rate and Wilson interval."""
    rows = []
    for (method, lo), cell in episodes.groupby(["method", "param_value"], sort=True):
        k, n = int(cell["success"].sum()), len(cell)
        low, high = wilson_interval(k, n)
        rows.append({"method": method, "bin_lo": float(lo), "n": n, "k": k, "rate": k / n,
                     "ci_low": low, "ci_high": high})
    return pd.DataFrame(rows)


def fisher_two_sided(k1: int, n1: int, k2: int, n2: int) -> float:
    """Two-sided Fisher exact test p of a 2 x 2 table (successes k of n, two groups): the
    summed probability of every table with the same margins no likelier than this one."""
    total, ones = n1 + n2, k1 + k2
    denom = math.comb(total, n1)

    def prob(a: int) -> float:
        return math.comb(ones, a) * math.comb(total - ones, n1 - a) / denom

    observed = prob(k1)
    support = range(max(0, ones - n2), min(ones, n1) + 1)
    return min(1.0, sum(p for p in map(prob, support) if p <= observed * (1 + 1e-9)))


def acceptance(rates: pd.DataFrame) -> list[tuple[str, bool, str]]:
    """Issue 38's checks: (what, met, the numbers)."""
    cell = {(r.method, r.bin_lo): r for r in rates.itertuples()}
    los = [lo for lo, _ in BINS]
    out = []
    for method, need, upto in (("impact_authors", 6, 10.0), ("vanilla_dp", 3, 1.0)):
        checked = [lo for lo in los if lo < upto and (method, lo) in cell]
        inside = [lo for lo, pub in zip(los, PUBLISHED[method], strict=True) if lo in checked
                  and cell[method, lo].ci_low <= pub <= cell[method, lo].ci_high]
        out.append((f"{method}: published rate inside our 95 % interval in >= {need} bins"
                    + (" up to 1 kg" if upto < 10 else ""), len(inside) >= need,
                    f"{len(inside)} of {len(checked)}"))
    ours = [cell[("impact", lo)] for lo in los if ("impact", lo) in cell]
    low = [f"{r.bin_lo:g}: {r.rate:.2f}" for r in ours if r.bin_lo < 8.0 and r.rate < 0.80]
    out.append(("impact >= 0.80 in every bin up to 8 kg", bool(ours) and not low,
                "; ".join(low) or "all"))
    pairs = [(cell[("impact", lo)], cell[("impact_authors", lo)]) for lo in los
             if ("impact", lo) in cell and ("impact_authors", lo) in cell]
    heavy = [(a, b) for a, b in pairs if a.bin_lo >= 4.0]
    ka, na = sum(a.k for a, _ in heavy), sum(a.n for a, _ in heavy)
    kb, nb = sum(b.k for _, b in heavy), sum(b.n for _, b in heavy)
    above = bool(heavy) and ka / na > kb / nb
    out.append(("impact pooled from 4 kg above impact_authors's", above,
                f"{ka}/{na} vs {kb}/{nb}" if heavy else "no rows"))
    worse = [f"{a.bin_lo:g} (p {fisher_two_sided(a.k, a.n, b.k, b.n):.3f})" for a, b in pairs
             if a.rate < b.rate and fisher_two_sided(a.k, a.n, b.k, b.n) < 0.05]
    out.append(("no bin where impact is below impact_authors (Fisher two-sided, 5 %)",
                bool(pairs) and not worse, "; ".join(worse) or "none"))
    return out


def markdown(rates: pd.DataFrame) -> str:
    """The table: our k/n (Wilson interval) per bin and method, theirs beside."""
    head = "| method | " + " | ".join(f"{lo:g}–{hi:g}" for lo, hi in BINS) + " | mean |"
    lines = [head, "|" + "---|" * (len(BINS) + 2)]
    for method in [m for m in ORDER if m in set(rates["method"])]:
        r = rates[rates["method"] == method].set_index("bin_lo")
        cells = [f"{r.loc[lo].k}/{r.loc[lo].n} ({r.loc[lo].ci_low:.2f}–{r.loc[lo].ci_high:.2f})"
                 if lo in r.index else "–" for lo, _ in BINS]
        lines.append(f"| {LABELS[method]} | " + " | ".join(cells)
                     + f" | {r['rate'].mean():.2f} |")
        if method in PUBLISHED:
            pub = PUBLISHED[method]
            lines.append("| ↳ published | " + " | ".join(f"{v:.2f}" for v in pub)
                         + f" | {np.mean(pub):.2f} |")
    return "\n".join(lines) + "\n"


def plot(rates: pd.DataFrame, path: Path) -> list[Path]:
    """Grouped bars per bin and the mean (ours), their published values as hollow markers."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    methods = [m for m in ORDER if m in set(rates["method"])]
    x, width = np.arange(len(BINS) + 1), 0.8 / max(1, len(methods))
    fig, ax = plt.subplots(figsize=(10, 3.8))
    for j, method in enumerate(methods):
        r = rates[rates["method"] == method].set_index("bin_lo")
        ys = [r.loc[lo].rate if lo in r.index else np.nan for lo, _ in BINS]
        ys.append(float(np.nanmean(ys)))
        xs = x - 0.4 + width * (j + 0.5)
        ax.bar(xs, ys, width, label=LABELS[method])
        if method in PUBLISHED:
            pub = [*PUBLISHED[method], float(np.mean(PUBLISHED[method]))]
            ax.scatter(xs, pub, marker="D", s=28, facecolors="white", edgecolors="black",
                       linewidths=1.2, zorder=3,  # on its own bar: white, black-edged
                       label="published (their figure)" if j == 0 else None)
    ax.set_xticks(x, [f"{lo:g}–{hi:g}" for lo, hi in BINS] + ["mean"])
    ax.set_xlabel("hammer mass bin [kg]")
    ax.set_ylabel("success rate")
    ax.set_ylim(0, 1.05)
    ax.set_title("HammerBasket: ours (bars, 95 % Wilson per bin in the table) and the authors' "
                 "published rates (white diamonds, on the bar of the same method)", fontsize=9)
    ax.legend(fontsize=7, ncol=3, loc="upper right")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    written = [path.with_suffix(f".{fmt}") for fmt in ("png", "pdf")]
    for out in written:
        fig.savefig(out, dpi=150)
    plt.close(fig)
    return written


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--table", type=Path, required=True,
                        help="a bin sweep's folder (its episodes.csv)")
    args = parser.parse_args(argv)
    csv = args.table / "episodes.csv"
    if not csv.is_file():
        parser.error(f"--table {args.table}: no episodes.csv there; valid: a sweep's folder")
    episodes = pd.read_csv(csv, keep_default_na=False)
    if set(episodes["param_name"]) != {"object_mass_bin"}:
        parser.error(f"--table {args.table}: not a bin sweep; valid: impact-eval --mass-bins")
    rates = bin_rates(episodes)
    text = markdown(rates) + "\n" + "\n".join(
        f"- {'met' if ok else 'NOT met'}: {what} ({numbers})"
        for what, ok, numbers in acceptance(rates)) + "\n"
    (args.table / "authors_figure.md").write_text(text)
    print(text, end="")
    for path in plot(rates, args.table / "plots" / "authors_figure"):
        print(f"  plot: {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
