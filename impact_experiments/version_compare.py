"""A table on the new env version against its twin on the old one, method by method (issue 59).

    python -m impact_experiments.version_compare [TABLE ...] [--version 2] [--out FILE]
    python -m impact_experiments.version_compare TABLE --wide [--methods impact,vanilla_dp]

For each named table (default: every table of ``results/manifest.json`` whose twin
``TABLE_vN`` is recorded there, ``rerun_tables --to-version N``), the rows of ``TABLE`` (the
old version) and ``TABLE_vN`` are compared per method, pooled over the table's cells:
successes k/n on each side, the two-sided Fisher p, and whether the new version is
**significantly lower** (its rate below and p < 5 %: issue 59 asks that no headline claim of
``default`` is); the cells whose successes moved; and the safety columns, as means over the
episodes: time above 20 N (``contact_over_20n_s``) and the sustained contact peak
(``peak_contact_sustained_n``, where both sides have it). Bad input (a table or twin not in
the manifest, a missing ``episodes.csv``) is one line, exit 2, before anything is written.

``--wide`` prints each table cell by cell instead: one row per method and version
(``-vN`` first, the old version under it), successes/episodes per cell, as the results
pages show them.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import pandas as pd

from impact_control.errors import InvalidArgumentError
from impact_eval.metrics import fisher_two_sided
from impact_eval.reproduce_manifest import load_manifest
from impact_experiments.rerun_tables import RESULTS

SAFETY = ("contact_over_20n_s", "peak_contact_sustained_n")
"""Safety columns compared (means over a method's episodes), where both sides have them."""


def twins(tables: dict, version: int) -> list[str]:
    """The tables of the manifest with a twin on ``version``, in the manifest's order."""
    return [t for t in tables if f"{t}_v{version}" in tables]


def compare_method(old: pd.DataFrame, new: pd.DataFrame) -> dict[str, object]:
    """One method's rows on each side, over the cells (``param_value``) both sides ran:
    pooled successes, Fisher p, moved cells, safety means; the cells only one side ran are
    named, not pooled (an unfinished twin must not look better for lacking its hard cells)."""
    cells_old, cells_new = set(old["param_value"]), set(new["param_value"])
    shared = sorted(cells_old & cells_new)
    old, new = old[old["param_value"].isin(shared)], new[new["param_value"].isin(shared)]
    k1, n1, k2, n2 = int(old["success"].sum()), len(old), int(new["success"].sum()), len(new)
    p = fisher_two_sided(k1, n1, k2, n2) if n1 and n2 else 1.0
    per_cell = pd.concat([old.groupby("param_value")["success"].sum().rename("old"),
                          new.groupby("param_value")["success"].sum().rename("new")], axis=1)
    moved = per_cell[per_cell["old"] != per_cell["new"]]
    one_side = [f"{v:g} only {side}" for side, only in (("old", cells_old - cells_new),
                                                        ("new", cells_new - cells_old))
                for v in sorted(only)]
    row: dict[str, object] = {
        "old": f"{k1}/{n1}", "new": f"{k2}/{n2}", "fisher_p": p,
        "significantly_lower": n1 > 0 and n2 > 0 and k2 / n2 < k1 / n1 and p < 0.05,
        "cells_moved": "; ".join([*(f"{v:g}: {int(r.old)}→{int(r.new)}"
                                    for v, r in moved.iterrows()), *one_side]) or "none"}
    for col in SAFETY:
        if col in old and col in new:  # means over the episodes that measured it
            row[col] = f"{old[col].mean():.2f} → {new[col].mean():.2f}"
    return row


def compare_table(old: pd.DataFrame, new: pd.DataFrame) -> pd.DataFrame:
    """:func:`compare_method` for every method of either side, in the old table's order; a
    method that one side lacks gets a row saying so."""
    rows = []
    for method in dict.fromkeys([*old["method"], *new["method"]]):
        a, b = old[old["method"] == method], new[new["method"] == method]
        if a.empty or b.empty:
            rows.append({"method": method, "old": f"{int(a['success'].sum())}/{len(a)}",
                         "new": f"{int(b['success'].sum())}/{len(b)}", "fisher_p": 1.0,
                         "significantly_lower": False,
                         "cells_moved": f"only in the {'old' if b.empty else 'new'} table"})
            continue
        rows.append({"method": method, **compare_method(a, b)})
    return pd.DataFrame(rows)


def markdown(name: str, version: int, rows: pd.DataFrame) -> str:
    """One table's comparison as a markdown section."""
    cols = ["method", "old", "new", "fisher_p", "significantly_lower", "cells_moved",
            *[c for c in SAFETY if c in rows]]
    head = (f"### `{name}` → `{name}_v{version}`\n\n| " + " | ".join(cols) + " |\n|"
            + "---|" * len(cols) + "\n")
    body = "".join("| " + " | ".join(_cell(c, r[c]) for c in cols) + " |\n"
                   for _, r in rows.iterrows())
    return head + body


def wide(old: pd.DataFrame, new: pd.DataFrame, version: int,
         methods: list[str] | None = None) -> str:
    """Both versions cell by cell as one markdown table: per method (``methods`` in that
    order, default every method of either side), its ``-v{version}`` row, then the old
    version's (labelled by the version in its ``env_id`` column, where it has one); a cell
    a side did not run is –."""
    cells = sorted(set(old["param_value"]) | set(new["param_value"]))
    order = methods or list(dict.fromkeys([*new["method"], *old["method"]]))
    lines = ["| method | env | " + " | ".join(f"{v:g}" for v in cells) + " |",
             "|---|---|" + "---|" * len(cells)]
    for method in order:
        for label, frame in ((f"-v{version}", new), (_version(old, "old"), old)):
            rows = frame[frame["method"] == method].groupby("param_value")["success"]
            k, n = rows.sum(), rows.size()
            lines.append(f"| `{method}` | {label} | " + " | ".join(
                f"{int(k[v])}/{int(n[v])}" if v in n.index else "–" for v in cells) + " |")
    return "\n".join(lines) + "\n"


def _version(frame: pd.DataFrame, fallback: str) -> str:
    """The ``-vN`` of a table's ``env_id`` column, or ``fallback`` without one."""
    ids = set(frame["env_id"]) if "env_id" in frame else set()
    return "/".join(sorted("-" + i.rsplit("-", 1)[1] for i in ids)) or fallback


def _cell(column: str, value: object) -> str:
    """One table cell: p to 3 significant digits, the verdict as yes (bold) / no, a value
    that is not there as –."""
    if isinstance(value, float) and math.isnan(value):
        return "–"
    if column == "fisher_p":
        return f"{value:.3g}"
    if column == "significantly_lower":
        return "**yes**" if value else "no"
    return str(value)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tables", nargs="*", metavar="TABLE", help="a table with a twin")
    parser.add_argument("--version", type=int, default=2, help="the twins' env version")
    parser.add_argument("--out", type=Path, help="also write the report here (markdown)")
    parser.add_argument("--wide", action="store_true",
                        help="each table cell by cell, both versions, instead of pooled")
    parser.add_argument("--methods", help="with --wide: these methods (comma list), in order")
    parser.add_argument("--results", type=Path, default=RESULTS, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    try:
        manifest = load_manifest(args.results)["tables"]
    except InvalidArgumentError as exc:
        parser.error(str(exc))
    valid = twins(manifest, args.version)
    for table in args.tables:
        if table not in valid:
            parser.error(f"{table}: no twin {table}_v{args.version} in the manifest; valid: "
                         f"{', '.join(valid) or 'none yet (rerun_tables --to-version)'}")
    if not valid:
        parser.error(f"no table of the manifest has a twin on -v{args.version}; valid: run "
                     f"rerun_tables --to-version {args.version} first")
    frames = {}
    for table in args.tables or valid:
        for name in (table, f"{table}_v{args.version}"):
            csv = args.results / manifest[name]["dir"] / "episodes.csv"
            if not csv.is_file():
                parser.error(f"{name}: no {csv}; valid: a recorded table's folder")
            frames[name] = pd.read_csv(csv, keep_default_na=False, na_values=["nan", "NaN"])
    if args.methods is not None and not args.wide:
        parser.error(f"--methods {args.methods}: only with --wide; valid: add --wide, or drop "
                     f"--methods (the pooled report covers every method)")
    methods = args.methods.split(",") if args.methods else None
    for table in args.tables or valid:
        known = set(frames[table]["method"]) | set(frames[f"{table}_v{args.version}"]["method"])
        if methods and not set(methods) <= known:
            parser.error(f"--methods {args.methods}: not in {table}; valid: "
                         f"{', '.join(sorted(known))}")
    text = "".join((f"### `{t}` → `{t}_v{args.version}`\n\n"
                    + wide(frames[t], frames[f"{t}_v{args.version}"], args.version, methods)
                    if args.wide else
                    markdown(t, args.version, compare_table(frames[t],
                                                            frames[f"{t}_v{args.version}"])))
                   + "\n" for t in args.tables or valid)
    print(text, end="")
    if args.out:
        args.out.write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
