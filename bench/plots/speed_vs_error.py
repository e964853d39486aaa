#!/usr/bin/env python3
"""speed_vs_error.csv (terrain_bench speed-vs-error) -> speed_vs_error.png, .svg.

One column of panels per scene: ms per frame (log) against the total relative
error (top) and the indirect light's (bottom). Each sweep's points are joined
in the order of its values and labelled with them; the paper's settings are a
point of their own, the engine's defaults are ringed, and the Pareto front of
total error against time (computed by the suite, the CSV's `pareto` column) is
drawn as a step line in the top row.
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plot_common  # noqa: E402 (after the path is set)
from matplotlib import ticker  # noqa: E402 (plot_common chooses the backend first)

SWEEP_LABELS = {
    "m": "environment azimuths m",
    "k_v": "levels per octave k_v",
    "o_v": "level offset o_v",
    "subsample": "sub-sampling",
    "bounces": "bounces",
}
ERRORS = [("total_rel_rmse", "total rel. RMSE (%)"), ("indirect_rel_rmse", "indirect rel. RMSE (%)")]


def sweep_lines(ax, rows, column, colours):
    """Each sweep's points in the order of its values, labelled with them."""
    for i, sweep in enumerate(SWEEP_LABELS):
        points = sorted((int(r["value"]), float(r["ms"]), 100 * float(r[column])) for r in rows if r["sweep"] == sweep)
        if not points:
            continue
        ax.plot([p[1] for p in points], [p[2] for p in points], "o-", color=colours[i], lw=1.2, ms=5,
                label=SWEEP_LABELS[sweep])
        defaults = {int(r["value"]) for r in rows if r["sweep"] == sweep and r["is_default"] == "1"}
        for value, ms, err in points:
            if value in defaults:
                continue  # the ring marks it; the sweeps' labels would pile up there
            ax.annotate(str(value), (ms, err), textcoords="offset points", xytext=(4, 4), fontsize=7,
                        color=colours[i])


def marked_points(ax, rows, column):
    """The paper's settings and the engine's defaults."""
    for r in rows:
        if r["sweep"] == "paper":
            ax.plot(float(r["ms"]), 100 * float(r[column]), "D", color="black", ms=6, label="paper's settings")
    defaults = [r for r in rows if r["is_default"] == "1"][:1]  # the defaults recur in every sweep
    for r in defaults:
        ax.plot(float(r["ms"]), 100 * float(r[column]), "o", mfc="none", mec="black", mew=1.8, ms=13,
                label="engine defaults")


def pareto_step(ax, rows):
    """The Pareto front of total error against time, as a step line."""
    front = sorted((float(r["ms"]), 100 * float(r["total_rel_rmse"])) for r in rows if r["pareto"] == "1")
    if front:
        ax.step([p[0] for p in front], [p[1] for p in front], where="post", color="0.35", ls="--", lw=1.2,
                marker="s", mfc="none", ms=9, label="Pareto front (total error)")


def log_axes(ax):
    """Log scales labelled with plain numbers (the errors span less than a decade: more labels there)."""
    for axis, set_scale, subs in ((ax.xaxis, ax.set_xscale, (1.0, 2.0, 3.0, 5.0)),
                                  (ax.yaxis, ax.set_yscale, (1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0))):
        set_scale("log")
        axis.set_major_locator(ticker.LogLocator(subs=subs))
        axis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        axis.set_minor_formatter(ticker.NullFormatter())


def main():
    folder = plot_common.results_dir(__doc__.splitlines()[0])
    rows = plot_common.read_csv(folder, "speed_vs_error.csv")
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    if not scenes:
        sys.exit(f"{os.path.basename(sys.argv[0])}: {folder}/speed_vs_error.csv has no rows")
    fig, axes = plot_common.figure_grid(len(ERRORS), len(scenes), 5.0 * len(scenes) + 2.6, 8.4)
    colours = [f"C{i}" for i in range(len(SWEEP_LABELS))]
    for col, scene in enumerate(scenes):
        scene_rows = [r for r in rows if r["scene"] == scene]
        for row, (column, label) in enumerate(ERRORS):
            ax = axes[row][col]
            sweep_lines(ax, scene_rows, column, colours)
            marked_points(ax, scene_rows, column)
            if row == 0:
                pareto_step(ax, scene_rows)
                ax.set_title(scene)
            log_axes(ax)
            ax.set_xlabel("ms per frame (2 threads)")
            ax.set_ylabel(label)
    axes[0][-1].legend(loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.suptitle("GI frame time against error: one setting varied from the engine's defaults")
    plot_common.save(fig, folder, "speed_vs_error")


if __name__ == "__main__":
    main()
