"""``summary.md`` and ``success.png`` of an ``impact_robosuite.experiment`` run, from its CSV."""

from __future__ import annotations

from pathlib import Path

DROP_LIFT_M = 0.04
"""A failed episode whose cube rose more than this [m] lost it after lifting it."""
METHOD_LABELS = {"osc": "robosuite OSC_POSE", "impedance": "our impedance", "impact": "IMPACT",
                 "impact_paper": "IMPACT (paper preset)"}


def write_report(out: Path) -> list[Path]:
    """Write the success table (successes / episodes, mean final lift) and the figure."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import pandas as pd

    rows = pd.read_csv(out / "episodes.csv")
    rows["dropped"] = (rows.success == 0) & (rows.max_lift_m > DROP_LIFT_M)
    cells = rows.groupby(["task", "method", "mass_kg"]).agg(
        successes=("success", "sum"), episodes=("success", "size"),
        final_lift_m=("final_lift_m", "median"), dropped=("dropped", "sum")).reset_index()
    lines = ["| task | mass [kg] | " + " | ".join(METHOD_LABELS.values()) + " |",
             "|---|---|" + "---|" * len(METHOD_LABELS)]
    for (task, mass), group in cells.groupby(["task", "mass_kg"]):
        by = group.set_index("method")
        items = [f"{int(by.successes[m])}/{int(by.episodes[m])} "
                 f"({by.final_lift_m[m] * 100:.1f} cm; {int(by.dropped[m])} dropped)"
                 if m in by.index else "–" for m in METHOD_LABELS]
        lines.append(f"| {task} | {mass:g} | " + " | ".join(items) + " |")
    summary = out / "summary.md"
    summary.write_text("Successes / episodes (median height of the cube above its start at the "
                       "last step; failed episodes in which the cube had been lifted more than "
                       f"{DROP_LIFT_M * 100:.0f} cm, i.e. dropped)\n\n" + "\n".join(lines) + "\n")
    tasks = sorted(cells.task.unique())
    fig, axes = plt.subplots(1, len(tasks), figsize=(4.2 * len(tasks), 3.4), squeeze=False)
    for ax, task in zip(axes[0], tasks, strict=True):
        for method, label in METHOD_LABELS.items():
            c = cells[(cells.task == task) & (cells.method == method)]
            if len(c):
                ax.plot(c.mass_kg, c.successes / c.episodes, "o-", label=label)
        ax.set(title=f"robosuite {task}, Panda", xlabel="cube mass [kg]",
               ylabel="success rate", ylim=(-0.05, 1.05))
        ax.grid(alpha=0.3)
    axes[0][0].legend(loc="lower left")
    fig.tight_layout()
    figure = out / "success.png"
    fig.savefig(figure, dpi=120)
    plt.close(fig)
    return [summary, figure]
